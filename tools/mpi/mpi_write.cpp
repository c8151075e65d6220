#include "tools/mpi/mpi_write.h"

#include <tbb/global_control.h>
#include <tbb/parallel_pipeline.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <exception>
#include <memory>
#include <utility>

#include "graph/chunk_output.h"
#include "graph/chunked_reconstruction.h"
#include "nodes/io/ply_mesh_file.h"
#include "tools/mpi/mpi_bytes.h"
#include "tools/mpi/mpi_tiles.h"

namespace meshflow::cli {
namespace {

// One rank's report to rank 0 after writing its rows.
struct RankWrite {
  chunk::RankTimes times;
  std::vector<std::pair<std::uint64_t, std::string>> failed;              // position, error
  std::string error;                                                      // its writing failed
  std::uint64_t vertices = 0, triangles = 0;                              // rows written
  std::vector<std::pair<std::uint64_t, chunk::SeamNeighbourhood>> parts;  // by position
  std::vector<std::array<std::uint64_t, 3>>
      rows;  // position, first face row, faces: its tiles (not sent)
};

void put_neighbourhood(io::ByteWriter& w, const chunk::SeamNeighbourhood& n) {
  put(w, static_cast<std::uint8_t>(n.any_feature ? 1 : 0));
  put_vector(w, n.vertex_index);
  put_vector(w, n.positions);
  put_vector(w, n.normals);
  put_vector(w, n.features);
  put_vector(w, n.seam);
  put_vector(w, n.near);
  put_vector(w, n.triangle_index);
  put_vector(w, n.triangles);
}

chunk::SeamNeighbourhood get_neighbourhood(io::ByteReader& r) {
  chunk::SeamNeighbourhood n;
  n.any_feature = get<std::uint8_t>(r, "seam features") != 0;
  n.vertex_index = get_vector<std::uint64_t>(r, "seam vertex rows");
  n.positions = get_vector<Eigen::Vector3f>(r, "seam positions");
  n.normals = get_vector<Eigen::Vector3f>(r, "seam normals");
  n.features = get_vector<std::uint8_t>(r, "seam feature flags");
  n.seam = get_vector<std::uint8_t>(r, "seam flags");
  n.near = get_vector<std::uint8_t>(r, "near-seam flags");
  n.triangle_index = get_vector<std::uint64_t>(r, "seam face rows");
  n.triangles = get_vector<Triangle>(r, "seam triangles");
  const std::size_t v = n.vertex_index.size();
  if (n.positions.size() != v || n.features.size() != v || n.seam.size() != v ||
      n.near.size() != v || (!n.normals.empty() && n.normals.size() != v) ||
      n.triangle_index.size() != n.triangles.size())
    r.fail("seam neighbourhood", "vectors of different lengths");
  return n;
}

std::vector<unsigned char> encode(const RankWrite& m) {
  io::ByteWriter w;
  put_rank_times(w, m.times);
  w.u64(m.failed.size());
  for (const auto& [position, error] : m.failed) {
    w.u64(position);
    put_string(w, error);
  }
  put_string(w, m.error);
  w.u64(m.vertices);
  w.u64(m.triangles);
  w.u64(m.parts.size());
  for (const auto& [position, n] : m.parts) {
    w.u64(position);
    put_neighbourhood(w, n);
  }
  return std::move(w.out);
}

RankWrite decode(const std::vector<unsigned char>& message, int from) {
  const std::string source = "rows written by rank " + std::to_string(from);
  io::ByteReader r(source, message);
  RankWrite m;
  m.times = get_rank_times(r);
  const std::uint64_t failed = r.u64("failed chunks");
  for (std::uint64_t i = 0; i < failed; ++i) {
    const std::uint64_t position = r.u64("failed chunk");
    m.failed.emplace_back(position, get_string(r, "chunk error"));
  }
  m.error = get_string(r, "write error");
  m.vertices = r.u64("vertex rows");
  m.triangles = r.u64("face rows");
  const std::uint64_t parts = r.u64("parts");
  for (std::uint64_t i = 0; i < parts; ++i) {
    const std::uint64_t position = r.u64("part");
    m.parts.emplace_back(position, get_neighbourhood(r));
  }
  return m;
}

// Writes one welded part into `file` at its rows (failed chunks skipped), keeps its seam
// neighbourhood (when the plan has flags) and frees it.
void write_part(ChunkResult& r, const chunk::ChunkGrid& grid, bool normals, bool flags,
                io::PlyMeshFile& file, RankWrite& mine) {
  if (!r.error.empty()) return;
  file.write_vertices(r.first_vertex, r.mesh);
  file.write_triangles(r.first_triangle, r.mesh.triangles);
  mine.vertices += r.mesh.vertices.size();
  mine.triangles += r.mesh.triangles.size();
  mine.rows.push_back({r.position, r.first_triangle, r.mesh.triangles.size()});
  if (flags) {
    chunk::SeamNeighbourhood n;
    chunk::add_seam_neighbourhood(r.mesh, r.flags, r.first_vertex, r.first_triangle,
                                  grid.voxel_size, grid.chunk_cells, kFeatureFlag, normals, n);
    mine.parts.emplace_back(r.position, std::move(n));
  }
  r = ChunkResult{};
}

// Writes this rank's parts into `file` at their rows, in order (each freed once written) and
// keeps their seam neighbourhoods. Parts not yet welded (weld_on_ranks() without weld_now,
// perhaps spilled) are welded here, a few at once, each just before it is written: memory is
// the parts in the pipeline, not all of them.
void write_parts(std::vector<ChunkResult>& results, const chunk::WeldPlan& weld,
                 const chunk::ChunkGrid& grid, bool normals, io::PlyMeshFile& file,
                 RankWrite& mine) {
  std::size_t next = 0;
  const auto threads = static_cast<std::size_t>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  const auto take = [&](tbb::flow_control& fc) -> ChunkResult* {
    if (next == results.size()) {
      fc.stop();
      return nullptr;
    }
    return &results[next++];
  };
  const auto weld_it = [&](ChunkResult* r) {
    if (!r->welded) weld_result(*r, weld);
    return r;
  };
  const auto write_it = [&](ChunkResult* r) {
    write_part(*r, grid, normals, weld.flags, file, mine);
  };
  tbb::parallel_pipeline(
      std::max<std::size_t>(2, threads),
      tbb::make_filter<void, ChunkResult*>(tbb::filter_mode::serial_in_order, take) &
          tbb::make_filter<ChunkResult*, ChunkResult*>(tbb::filter_mode::parallel, weld_it) &
          tbb::make_filter<ChunkResult*, void>(tbb::filter_mode::serial_in_order, write_it));
}

}  // namespace

RanksWritten write_on_ranks(const std::string& output, std::vector<ChunkResult>& results,
                            const chunk::WeldPlan& weld, const chunk::ChunkGrid& grid,
                            const Eigen::Vector3d& origin, std::size_t chunks,
                            const std::string& tiles_dir,
                            const std::vector<chunk::ChunkFile>& files, chunk::PhaseClock& clock,
                            int rank, int ranks) {
  const io::PlyMeshLayout layout = chunk::streamed_layout(weld, origin);
  const bool any = weld.triangles > 0;
  RankWrite mine;
  for (const ChunkResult& r : results)
    if (!r.error.empty()) mine.failed.emplace_back(r.position, r.error);
  // Rank 0 plans the file (its header and size); the others wait to hear that it exists.
  std::unique_ptr<io::PlyMeshFile> file;
  if (any) {
    std::string created;
    if (rank == 0) {
      clock.begin("create", true);
      try {
        file = std::make_unique<io::PlyMeshFile>(output, layout, weld.vertices, weld.triangles,
                                                 origin);
      } catch (const std::exception& e) {
        created = e.what();
      }
    } else {
      clock.wait("create");
    }
    std::vector<unsigned char> verdict(created.begin(), created.end());
    broadcast_bytes(verdict);
    created.assign(verdict.begin(), verdict.end());
    if (!created.empty()) {
      mine.error = created;
    } else {
      clock.begin("write", false);
      try {
        if (rank == 0) {
          write_parts(results, weld, grid, layout.normals, *file, mine);
        } else {
          io::PlyMeshFile joined(output, layout, weld.vertices, weld.triangles, origin,
                                 io::PlyMeshFile::Role::kJoin);
          write_parts(results, weld, grid, layout.normals, joined, mine);
          joined.close();
        }
      } catch (const std::exception& e) {
        mine.error = e.what();
      }
    }
  }
  mine.times = {rank, chunks, chunk::peak_resident_bytes(), clock.phases()};
  RanksWritten written;
  TileJob tiles{output,    layout, weld.vertices, weld.triangles, origin,
                tiles_dir, grid,   &files,        mine.rows,      chunks};
  if (rank != 0) {
    clock.end();
    mine.times.phases = clock.phases();
    send_bytes(encode(mine), 0);
    for (const auto& f : mine.failed) written.failed.push_back(f.second);
    if (!tiles_dir.empty()) write_tiles_on_ranks(tiles, "", clock, rank, ranks);
    return written;
  }

  // Rank 0: every rank's rows and seams, then the seams finished and the file committed.
  clock.begin("gather", true);
  std::vector<RankWrite> all;
  all.push_back(std::move(mine));
  for (int from = 1; from < ranks; ++from) {
    const std::vector<unsigned char> received = receive_bytes(from);
    written.gathered_bytes += received.size();
    all.push_back(decode(received, from));
  }
  std::vector<std::pair<std::uint64_t, std::string>> failed;
  std::vector<std::pair<std::uint64_t, chunk::SeamNeighbourhood*>> parts;
  std::uint64_t vertices = 0, triangles = 0;
  for (RankWrite& m : all) {
    written.times.push_back(m.times);
    failed.insert(failed.end(), m.failed.begin(), m.failed.end());
    if (written.error.empty() && !m.error.empty())
      written.error = "rank " + std::to_string(m.times.rank) + ": " + m.error;
    vertices += m.vertices;
    triangles += m.triangles;
    for (auto& [position, n] : m.parts) parts.emplace_back(position, &n);
  }
  std::sort(failed.begin(), failed.end());
  for (const auto& f : failed) written.failed.push_back(f.second);
  if (!any) {
    written.error = "no surface was extracted";
  } else if (written.error.empty()) {
    try {
      std::sort(parts.begin(), parts.end(),
                [](const auto& a, const auto& b) { return a.first < b.first; });
      chunk::SeamNeighbourhood seams;
      for (const auto& part : parts) {
        seams.append(*part.second);
        *part.second = chunk::SeamNeighbourhood{};
      }
      clock.begin("finish", true);  // the seams: flips and normals, their rows rewritten
      file->add_rows_written_elsewhere(vertices - all.front().vertices,
                                       triangles - all.front().triangles);
      chunk::finish_seam_rows(seams, *file, &written.rewritten);
      if (!tiles_dir.empty()) file->sync();  // the ranks read their tiles' finished rows
    } catch (const std::exception& e) {
      written.error = e.what();
    }
  }
  if (!tiles_dir.empty()) {  // every rank its own chunks' tiles, rank 0 the index
    const TilesWritten tiled = write_tiles_on_ranks(
        tiles, written.error.empty() ? "" : "rank 0 did not finish the output", clock, rank, ranks);
    for (const chunk::RankTimes& t : tiled.others) written.times.at(t.rank) = t;
    if (written.error.empty()) written.error = tiled.error;
    written.tiles = tiled.tiles;
  }
  if (written.error.empty()) {
    try {
      file->commit();
    } catch (const std::exception& e) {
      written.error = e.what();
    }
  }
  clock.end();
  return written;
}

}  // namespace meshflow::cli
