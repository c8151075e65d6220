#include "tools/mpi/mpi_weld.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdio>
#include <map>

#include "graph/chunked_reconstruction.h"
#include "nodes/chunk/mesh_spill.h"
#include "nodes/chunk/seam_weld.h"
#include "tools/mpi/mpi_bytes.h"

namespace meshflow::cli {
namespace {

// A chunk's seam summary without its owner's per-vertex pieces.
void put_seams(io::ByteWriter& w, const chunk::ChunkSeams& s) {
  w.u64(s.vertices);
  w.u64(s.used_apart);
  put(w, static_cast<std::uint8_t>((s.normals ? 1 : 0) | (s.colors ? 2 : 0) | (s.flags ? 4 : 0)));
  put_vector(w, s.piece_triangles);
  put_vector(w, s.seam_index);
  put_vector(w, s.seam_key);
  put_vector(w, s.seam_used);
  put_vector(w, s.used_apart_before);
  put_vector(w, s.edges);
}

chunk::ChunkSeams get_seams(io::ByteReader& r) {
  chunk::ChunkSeams s;
  s.vertices = static_cast<std::uint32_t>(r.u64("seam summary vertices"));
  s.used_apart = static_cast<std::uint32_t>(r.u64("seam summary used vertices"));
  const auto has = get<std::uint8_t>(r, "seam summary attributes");
  s.normals = (has & 1) != 0;
  s.colors = (has & 2) != 0;
  s.flags = (has & 4) != 0;
  s.piece_triangles = get_vector<std::uint64_t>(r, "piece triangles");
  s.seam_index = get_vector<std::uint32_t>(r, "seam vertices");
  s.seam_key = get_vector<std::uint64_t>(r, "seam keys");
  s.seam_used = get_vector<std::uint8_t>(r, "seam use");
  s.used_apart_before = get_vector<std::uint32_t>(r, "seam order");
  s.edges = get_vector<chunk::SeamEdge>(r, "seam edges");
  const std::size_t n = s.seam_index.size();
  if (s.seam_key.size() != n || s.seam_used.size() != n || s.used_apart_before.size() != n)
    r.fail("seam summary", "seam vectors of different lengths");
  return s;
}

}  // namespace

void summarize_result(ChunkResult& result, float voxel_size, int chunk_cells) {
  if (result.error.empty())
    result.seams =
        chunk::summarize_seams(result.mesh, result.flags, voxel_size, chunk_cells, kFeatureFlag);
}

void spill_result(ChunkResult& result, const std::string& path) {
  if (!result.error.empty()) return;
  chunk::SpilledMesh spilled;
  spilled.mesh = std::move(result.mesh);
  spilled.flags = std::move(result.flags);
  spilled.vertex_piece = std::move(result.seams.vertex_piece);
  result.mesh = TriangleMesh{};
  result.flags = {};
  result.seams.vertex_piece = {};
  chunk::write_mesh_spill(path, spilled);
  result.spill = path;
}

void weld_result(ChunkResult& r, const chunk::WeldPlan& plan) {
  if (!r.error.empty()) return;
  if (!r.spill.empty()) {
    chunk::SpilledMesh spilled = chunk::read_mesh_spill(r.spill);
    std::remove(r.spill.c_str());
    r.spill.clear();
    r.mesh = std::move(spilled.mesh);
    r.flags = std::move(spilled.flags);
    r.seams.vertex_piece = std::move(spilled.vertex_piece);
  }
  std::vector<std::uint8_t> kept;
  r.mesh = chunk::weld_chunk(r.mesh, r.flags, r.seams, plan, r.plan_index, &kept);
  r.flags = std::move(kept);
  r.seams = chunk::ChunkSeams{};
  r.welded = true;
}

chunk::WeldPlan weld_on_ranks(std::vector<ChunkResult>& results, chunk::PhaseClock& clock, int rank,
                              int ranks, bool weld_now) {
  clock.wait("exchange");  // the slowest rank's chunks, then every rank's summaries
  io::ByteWriter w;
  std::uint64_t ok = 0;
  for (const ChunkResult& r : results) ok += r.error.empty() ? 1 : 0;
  w.u64(ok);
  for (const ChunkResult& r : results)
    if (r.error.empty()) {
      w.u64(r.position);
      put_seams(w, r.seams);
    }
  // Rank 0 joins every rank's summaries and hands them to all.
  std::vector<unsigned char> all;
  if (rank == 0) {
    all = std::move(w.out);
    for (int from = 1; from < ranks; ++from) {
      const std::vector<unsigned char> received = receive_bytes(from);
      all.insert(all.end(), received.begin(), received.end());
    }
  } else {
    send_bytes(w.out, 0);
  }
  broadcast_bytes(all);
  if (rank == 0)
    clock.begin("seams", true);
  else
    clock.wait("seams");  // the same plan as rank 0's, made at the same time
  std::map<std::uint64_t, chunk::ChunkSeams> by_position;  // every chunk meshed, in order
  {
    const std::string source = "seam summaries";
    io::ByteReader r(source, all);
    for (int from = 0; from < ranks; ++from) {
      const std::uint64_t count = r.u64("chunks");
      for (std::uint64_t c = 0; c < count; ++c) {
        const std::uint64_t position = r.u64("position");
        by_position[position] = get_seams(r);
      }
    }
  }
  std::map<std::uint64_t, std::size_t> index;  // position -> index in the plan
  std::vector<const chunk::ChunkSeams*> chunks;
  std::vector<std::uint64_t> first_triangle;  // per plan index: its part's first face row
  std::uint64_t triangles = 0;
  for (const auto& entry : by_position) {
    index[entry.first] = chunks.size();
    chunks.push_back(&entry.second);
    first_triangle.push_back(triangles);
    for (const std::uint64_t t : entry.second.piece_triangles) triangles += t;
  }
  chunk::WeldPlan plan = chunk::plan_weld(chunks);
  by_position.clear();
  for (ChunkResult& r : results) {
    if (!r.error.empty()) continue;
    r.plan_index = index.at(r.position);
    r.first_vertex = plan.vertex_offset[r.plan_index];
    r.first_triangle = first_triangle[r.plan_index];
  }
  if (!weld_now) {
    clock.end();
    return plan;
  }
  clock.begin("weld", false);
  tbb::parallel_for(std::size_t{0}, results.size(),
                    [&](std::size_t i) { weld_result(results[i], plan); });
  clock.end();
  plan.seam_target = {};
  plan.turn = {};
  return plan;
}

}  // namespace meshflow::cli
