// meshflow-mpi reconstruct: the out-of-core reconstruction (graph/chunked_reconstruction.h)
// spread over MPI ranks.
//
//   mpirun -n N meshflow-mpi reconstruct IN -o OUT --chunk S [--voxel V] [--chunk-dir DIR] ...
//
// Rank 0 streams the input into chunk files under --chunk-dir (a directory every rank sees: a
// shared file system on a cluster) and broadcasts the chunk list; the chunks, in Morton order,
// are split into N contiguous runs of about equal point counts (static assignment along the
// space-filling curve); each rank meshes its run through its own flow graph and sends the chunk
// meshes to rank 0, which welds every chunk in Morton order (its own as they come out, then the
// other ranks' in rank order), trims the rim, optimizes and writes OUT. Welding and the seam
// orientation see the chunks in the one-process order, so the mesh is the same for any N (and
// equals `meshflow reconstruct --chunk`).

#include <mpi.h>

#include <CLI/CLI.hpp>

#include <memory>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "graph/chunked_reconstruction.h"
#include "nodes/io/mesh_writers.h"
#include "runtime/error.h"
#include "runtime/threads.h"
#include "runtime/tracing.h"
#include "tools/mpi/mpi_bytes.h"
#include "tools/mpi/mpi_commands.h"
#include "tools/pipeline_options.h"

namespace meshflow::cli {
namespace {

// What rank 0 tells every rank after partitioning ("" error: go on).
struct Plan {
  std::string error;
  chunk::ChunkGrid grid;
  chunk::ChunkRows rows;
  std::vector<chunk::ChunkFile> files;
};

std::vector<char> encode(const Plan& plan) {
  Bytes b;
  b.put_string(plan.error);
  b.put(plan.grid);
  b.put(plan.rows.normals);
  b.put(plan.rows.colors);
  b.put(plan.rows.origin);
  b.put<std::uint64_t>(plan.files.size());
  for (const chunk::ChunkFile& f : plan.files) {
    b.put(f.index);
    b.put(f.core_points);
    b.put(f.points);
    b.put_string(f.path);
  }
  return b.data;
}

Plan decode_plan(std::vector<char> data) {
  Bytes b;
  b.data = std::move(data);
  Plan plan;
  plan.error = b.get_string();
  plan.grid = b.get<chunk::ChunkGrid>();
  plan.rows.normals = b.get<bool>();
  plan.rows.colors = b.get<bool>();
  plan.rows.origin = b.get<Eigen::Vector3d>();
  plan.files.resize(b.get<std::uint64_t>());
  for (chunk::ChunkFile& f : plan.files) {
    f.index = b.get<Eigen::Vector3i>();
    f.core_points = b.get<std::uint64_t>();
    f.points = b.get<std::uint64_t>();
    f.path = b.get_string();
  }
  return plan;
}

// A rank's chunk meshes in its order, each with its rim verdicts (Frame::beyond_data).
void encode_chunk(Bytes& b, const Frame& frame) {
  b.put_vector(frame.mesh.vertices);
  b.put_vector(frame.mesh.normals);
  b.put_vector(frame.mesh.colors);
  b.put_vector(frame.mesh.triangles);
  b.put_vector(frame.beyond_data);
}

// Adds the chunk meshes of one rank's message to `stitcher`, in the rank's order.
void add_chunks(Bytes& b, std::uint64_t chunks, chunk::MeshStitcher& stitcher) {
  for (std::uint64_t c = 0; c < chunks; ++c) {
    TriangleMesh mesh;
    mesh.vertices = b.get_vector<Eigen::Vector3f>();
    mesh.normals = b.get_vector<Eigen::Vector3f>();
    mesh.colors = b.get_vector<Rgb8>();
    mesh.triangles = b.get_vector<Triangle>();
    stitcher.add(mesh, b.get_vector<std::uint8_t>());
  }
}

struct Options {
  std::string input, columns, output;
  PipelineOptions pipeline;
  ChunkingConfig chunking;
};

int run(const Options& o, int rank, int ranks) {
  ThreadLimit limit(o.pipeline.threads);
  const ReconstructionConfig config = o.pipeline.config();
  const double t0 = monotonic_seconds();
  Plan plan;
  std::unique_ptr<chunk::ChunkStore> store;  // rank 0: owns the directory until the end
  if (rank == 0) {
    try {
      io::check_mesh_output_format(o.output);
      float voxel = 0.0f;
      store = partition_input(o.input, o.columns, config, o.chunking, plan.files, voxel);
      plan.grid = store->grid();
      plan.rows = store->rows();
    } catch (const std::exception& e) {
      plan.error = e.what();
    }
  }
  std::vector<char> message = rank == 0 ? encode(plan) : std::vector<char>();
  broadcast_bytes(message);
  if (rank != 0) plan = decode_plan(std::move(message));
  if (!plan.error.empty()) {
    if (rank == 0) std::fprintf(stderr, "meshflow-mpi: error: %s\n", plan.error.c_str());
    return 1;
  }
  const double partition_s = monotonic_seconds() - t0;

  // This rank's contiguous run of chunks along the Morton curve, of about 1/N of the points:
  // chunk i goes to the rank whose share of the running point count holds its midpoint.
  const std::size_t n = plan.files.size();
  std::uint64_t all_points = 0;
  for (const chunk::ChunkFile& f : plan.files) all_points += f.points;
  std::vector<chunk::ChunkFile> mine;
  std::uint64_t before = 0;
  for (const chunk::ChunkFile& f : plan.files) {
    const double middle = (static_cast<double>(before) + 0.5 * static_cast<double>(f.points)) /
                          static_cast<double>(std::max<std::uint64_t>(all_points, 1));
    if (std::min(static_cast<int>(middle * ranks), ranks - 1) == rank) mine.push_back(f);
    before += f.points;
  }
  // Rank 0 welds its own chunks as they come out of its graph, then the other ranks' chunk
  // meshes in rank order: the chunks meet the stitcher in Morton order, as in one process, so
  // welding and orientation give the same mesh for any number of ranks.
  double t = monotonic_seconds();
  chunk::MeshStitcher stitcher(plan.grid.voxel_size, plan.grid.chunk_cells);
  ChunkedReport report;
  Bytes outgoing;
  std::uint64_t sent_chunks = 0;
  mesh_chunk_files(mine, plan.grid, plan.rows, config, o.chunking.in_flight, o.input,
                   [&](const FramePtr& frame) {
                     if (rank == 0) return collect_chunk_frame(*frame, stitcher, report);
                     if (!frame->ok()) {
                       report.failed.push_back(frame->name + ": " + frame->error);
                       return;
                     }
                     encode_chunk(outgoing, *frame);
                     ++sent_chunks;
                     frame->mesh = TriangleMesh{};
                   });
  report.mesh_s = monotonic_seconds() - t;
  std::fprintf(stderr, "meshflow-mpi: rank %d/%d: %zu chunks meshed in %.2f s\n", rank, ranks,
               mine.size(), report.mesh_s);
  for (const std::string& failure : report.failed)
    std::fprintf(stderr, "meshflow-mpi: rank %d: chunk failed, its cells are missing: %s\n", rank,
                 failure.c_str());
  if (rank != 0) {
    Bytes chunks;
    chunks.put(sent_chunks);
    chunks.data.insert(chunks.data.end(), outgoing.data.begin(), outgoing.data.end());
    outgoing = Bytes();
    send_bytes(chunks.data, 0);
    return 0;
  }
  t = monotonic_seconds();
  std::size_t gathered_bytes = 0;
  for (int from = 1; from < ranks; ++from) {
    Bytes b;
    b.data = receive_bytes(from);
    gathered_bytes += b.data.size();
    const auto chunks = b.get<std::uint64_t>();
    add_chunks(b, chunks, stitcher);
  }
  const double gather_s = monotonic_seconds() - t;
  ChunkedReport total;
  const TriangleMesh mesh = finish_chunked_mesh(stitcher, config, plan.grid.voxel_size, total);
  if (mesh.empty()) {
    std::fprintf(stderr, "meshflow-mpi: error: %s: no surface was extracted\n", o.input.c_str());
    return 1;
  }
  io::write_mesh(o.output, mesh, plan.rows.origin);
  std::printf("input      %s: %zu chunks of %d cells at voxel %.4f m over %d ranks\n",
              o.input.c_str(), n, plan.grid.chunk_cells, plan.grid.voxel_size, ranks);
  std::printf("mesh       %zu vertices, %zu triangles\n", mesh.vertices.size(),
              mesh.triangles.size());
  std::printf(
      "time       %.1f s: partition %.1f s, rank 0 chunks %.1f s, gather %.1f s (%.1f MB), "
      "stitch %.1f s, optimize %.1f s\n",
      monotonic_seconds() - t0, partition_s, report.mesh_s, gather_s,
      static_cast<double>(gathered_bytes) / 1e6, total.stitch_s, total.optimize_s);
  std::printf("output     %s\n", o.output.c_str());
  return 0;
}

}  // namespace
}  // namespace meshflow::cli

namespace meshflow::cli {

void add_mpi_reconstruct(CLI::App* cmd, const MpiWorld& world, int& status) {
  auto o = std::make_shared<Options>();
  cmd->add_option("input", o->input, "Point cloud: .ply (streamed) .pcd .las .xyz .txt .3d")
      ->required();
  cmd->add_option("-o,--output", o->output, "Output mesh: .ply .obj .stl .off .glb")->required();
  cmd->add_option("--columns", o->columns, "Text clouds: the columns' meaning");
  cmd->add_option("--chunk", o->chunking.chunk_size, "Chunk edge, metres")->required();
  cmd->add_option("--chunk-overlap", o->chunking.overlap_voxels,
                  "Voxels of points each chunk sees beyond its own cells");
  cmd->add_option("--chunk-dir", o->chunking.directory,
                  "Where rank 0 writes the chunk files; every rank must see it (a shared file "
                  "system on a cluster)");
  cmd->add_option("--chunks-in-flight", o->chunking.in_flight, "Chunks meshed at once per rank");
  add_pipeline_options(cmd, o->pipeline);
  cmd->callback([o, world, &status] { status = run(*o, world.rank, world.ranks); });
}

}  // namespace meshflow::cli
