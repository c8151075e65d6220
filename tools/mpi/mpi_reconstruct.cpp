// meshflow-mpi reconstruct: the out-of-core reconstruction (graph/chunked_reconstruction.h)
// spread over MPI ranks.
//
//   mpirun -n N meshflow-mpi reconstruct IN -o OUT --chunk S [--voxel V] [--chunk-dir DIR] ...
//
// A binary PLY is partitioned by every rank at once, each reading only its own byte range (for
// its part of the whole-input sample that decides the voxel and the method, and for its part of
// the chunk files; tools/mpi/mpi_partition.h); other formats are streamed by rank 0 alone. The
// chunk files go under --chunk-dir (a directory every rank sees: a shared file system on a
// cluster); rank 0 broadcasts the chunk list. The chunks go out from a queue
// on rank 0 in Morton order, each to the rank that asks first (rank 0's own graph included); each
// rank meshes what it gets through its own flow graph (each chunk finished in place) and welds
// its own chunks once every rank's seam summaries are known (tools/mpi/mpi_weld.h); rank 0
// plans OUT's header, every rank writes its welded parts into it at their rows, and rank 0
// finishes the seams (with --tiles: writes each chunk's finished rows as its tile) and renames
// the file into place (not streamed: another format, or --finish-after-stitch: rank 0 gathers
// the parts and writes the whole mesh, and with --tiles sends each rank the tiles of the chunks
// it meshed, which it writes; tools/mpi/mpi_tiles.h). The weld and
// the seam orientation are planned over the chunks in the one-process order, so the mesh is
// the same for any N and any assignment (and equals `meshflow reconstruct --chunk`).

#include <mpi.h>

#include <CLI/CLI.hpp>

#include <memory>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "graph/chunk_output.h"
#include "graph/chunked_reconstruction.h"
#include "nodes/chunk/phase_times.h"
#include "nodes/extract/extract_surface.h"
#include "nodes/io/mesh_writers.h"
#include "options/json_report.h"
#include "runtime/error.h"
#include "runtime/threads.h"
#include "runtime/tracing.h"
#include "tools/mpi/mpi_bytes.h"
#include "tools/mpi/mpi_commands.h"
#include "tools/mpi/mpi_partition.h"
#include "tools/mpi/mpi_tiles.h"
#include "tools/mpi/mpi_weld.h"
#include "tools/mpi/mpi_write.h"
#include "tools/pipeline_options.h"

namespace meshflow::cli {
namespace {

// What rank 0 tells every rank after partitioning ("" error: go on).
struct Plan {
  std::string error;
  chunk::ChunkGrid grid;
  chunk::ChunkRows rows;
  InputDecisions decided;
  std::vector<chunk::ChunkFile> files;
};

std::vector<unsigned char> encode(const Plan& plan) {
  io::ByteWriter w;
  put_string(w, plan.error);
  put(w, plan.grid);
  put_rows(w, plan.rows);
  put(w, plan.decided);
  put_chunk_files(w, plan.files);
  return std::move(w.out);
}

Plan decode_plan(const std::vector<unsigned char>& message) {
  const std::string source = "chunk plan from rank 0";  // the reader keeps a reference
  io::ByteReader r(source, message);
  Plan plan;
  plan.error = get_string(r, "error");
  plan.grid = get<chunk::ChunkGrid>(r, "grid");
  plan.rows = get_rows(r);
  plan.decided = get<InputDecisions>(r, "decisions");
  plan.files = get_chunk_files(r);
  return plan;
}

constexpr int kRequestTag = 2;  // a rank asks rank 0 for a chunk
constexpr int kAnswerTag = 3;   // rank 0 answers with its position in the plan, or -1

// A rank's chunk meshes and its timing, for rank 0.
std::vector<unsigned char> encode(const std::vector<ChunkResult>& results,
                                  const chunk::RankTimes& times) {
  io::ByteWriter w;
  put_rank_times(w, times);
  w.u64(results.size());
  for (const ChunkResult& r : results) {
    w.u64(r.position);
    put_string(w, r.error);
    put_mesh(w, r.mesh);
    put_vector(w, r.flags);
  }
  return std::move(w.out);
}

// Appends the chunk meshes of what encode() sent from rank `from` to `results`; returns its
// timing.
chunk::RankTimes decode_into(const std::vector<unsigned char>& message, int from,
                             std::vector<ChunkResult>& results) {
  const std::string source = "chunk meshes from rank " + std::to_string(from);
  io::ByteReader r(source, message);
  chunk::RankTimes times = get_rank_times(r);
  const std::uint64_t count = r.u64("chunks");
  for (std::uint64_t i = 0; i < count; ++i) {
    ChunkResult c;
    c.position = r.u64("position");
    c.error = get_string(r, "error");
    c.mesh = get_mesh(r);
    c.flags = get_vector<std::uint8_t>(r, "vertex flags");
    results.push_back(std::move(c));
  }
  return times;
}

// Rank 0's main thread: answers every other rank's requests for a chunk with take()'s next one
// until each has been told there is none left. Polls every kQueuePoll instead of blocking in
// MPI_Recv, which in Open MPI spins on a core that rank 0's own graph needs.
void serve_chunk_queue(const std::function<long long()>& take, int ranks) {
  constexpr auto kQueuePoll = std::chrono::microseconds(500);
  for (int finished = 0; finished < ranks - 1;) {
    int request = 0, arrived = 0;
    MPI_Status status;
    MPI_Iprobe(MPI_ANY_SOURCE, kRequestTag, MPI_COMM_WORLD, &arrived, &status);
    if (!arrived) {
      std::this_thread::sleep_for(kQueuePoll);
      continue;
    }
    MPI_Recv(&request, 1, MPI_INT, status.MPI_SOURCE, kRequestTag, MPI_COMM_WORLD, &status);
    const long long position = take();
    MPI_Send(&position, 1, MPI_LONG_LONG, status.MPI_SOURCE, kAnswerTag, MPI_COMM_WORLD);
    if (position < 0) ++finished;
  }
}

struct Options {
  std::string input, columns, output;
  std::string chunk;  ///< --chunk: "auto" or metres
  PipelineOptions pipeline;
  ChunkingConfig chunking;
  bool json = false;  ///< --json: rank 0 prints one JSON document instead of the text report
  std::string tiles;  ///< --tiles DIR: the mesh also as one file per chunk and an index
};

// --chunk as `reconstruct --chunk` takes it: "auto" lets the chunks in flight have half of
// --max-memory (the rest: the seams and the output's buffers), 1 GiB when none is given.
ChunkingConfig chunking_of(const Options& o, const ReconstructionConfig& config) {
  ChunkingConfig chunking = o.chunking;
  chunking.chunk_size = o.chunk == "auto" ? 0.0f : std::stof(o.chunk);
  chunking.memory_budget = o.pipeline.max_memory.empty() ? 0 : config.max_memory_bytes / 2;
  return chunking;
}

// Rank 0's report: the text lines, or with --json one document (the keys of `reconstruct
// --chunk --json` where they mean the same, plus every rank's timing).
void print_report(const Options& o, const Plan& plan, const ChunkedReport& report,
                  const std::vector<chunk::RankTimes>& times, std::size_t gathered_bytes,
                  std::size_t tiles, double wall, int threads) {
  const chunk::SerialFraction serial = chunk::serial_fraction(times, wall);
  const float voxel = plan.grid.voxel_size;
  if (o.json) {
    const nlohmann::json doc = {
        {"input", o.input},
        {"output", o.output},
        {"processes", times.size()},
        {"threads", threads},
        {"wall_s", wall},
        {"voxel", voxel},
        {"chunk", {{"cells", plan.grid.chunk_cells}, {"metres", plan.grid.chunk_cells * voxel}}},
        {"chunks", plan.files.size()},
        {"failed_chunks", report.failed},
        {"seam_vertices", report.seam_vertices},
        {"gathered_bytes", gathered_bytes},
        {"tiles", tiles},
        {"mesh",
         {{"vertices", report.output_vertices},
          {"triangles", report.output_triangles},
          {"extract", extract_method_name(plan.decided.method)}}},
        {"optimize", options::optimize_json(report.optimize)},
        {"timing", options::chunked_timing_json(times, wall)}};
    std::printf("%s\n", doc.dump(2).c_str());
    return;
  }
  std::printf("input      %s: %zu chunks of %d cells at voxel %.4f m over %zu ranks\n",
              o.input.c_str(), plan.files.size(), plan.grid.chunk_cells, voxel, times.size());
  std::printf("mesh       %llu vertices, %llu triangles\n",
              static_cast<unsigned long long>(report.output_vertices),
              static_cast<unsigned long long>(report.output_triangles));
  const std::vector<chunk::PhaseTime>& own = times.front().phases;
  const auto phase = [&](const char* name) { return chunk::phase_wall(own, name); };
  std::printf(
      "time       %.1f s: decide %.1f s, partition %.1f s, chunks %.1f s, seams %.1f s, weld "
      "%.1f s, write %.1f s, gather %.1f s (%.1f MB), stitch %.1f s, finish %.1f s, tiles "
      "%.1f s\n",
      wall, phase("decide"), phase("setup") + phase("partition") + phase("join"), phase("chunks"),
      phase("seams"), phase("weld"), phase("create") + phase("write"), phase("gather"),
      static_cast<double>(gathered_bytes) / 1e6, phase("stitch"), phase("finish"), phase("tiles"));
  std::printf("serial     %.1f s of %.1f s on one core (Amdahl: f = %.3f, at most %.1fx faster)\n",
              serial.serial_s, serial.serial_s + serial.parallel_work_s, serial.fraction,
              serial.max_speedup);
  std::printf("output     %s\n", o.output.c_str());
  if (tiles > 0) std::printf("tiles      %zu in %s (tiles.json)\n", tiles, o.tiles.c_str());
}

int run(const Options& o, int rank, int ranks) {
  ThreadLimit limit(o.pipeline.threads);
  const ReconstructionConfig config = o.pipeline.config();
  const double t0 = monotonic_seconds();
  ChunkedReport report;  // its clock times this rank's phases
  chunk::PhaseClock& clock = report.clock;
  Plan plan;
  std::unique_ptr<chunk::ChunkStore> store;  // rank 0: owns the directory until the end
  const ChunkingConfig chunking = chunking_of(o, config);
  InputParts parts;
  try {
    parts = input_parts(o.input, o.columns, static_cast<std::size_t>(ranks));
  } catch (const std::exception&) {
    parts = InputParts{};  // rank 0's partition names the problem
  }
  if (parts.by_byte_range) {  // every rank reads its own byte range
    if (rank == 0) {
      try {
        io::check_mesh_output_format(o.output);
      } catch (const std::exception& e) {
        plan.error = e.what();
      }
    }
    std::vector<unsigned char> verdict = rank == 0 ? encode(plan) : std::vector<unsigned char>();
    broadcast_bytes(verdict);
    if (rank != 0) plan = decode_plan(verdict);
    if (!plan.error.empty()) {
      if (rank == 0) std::fprintf(stderr, "meshflow-mpi: error: %s\n", plan.error.c_str());
      return 1;
    }
    RankedPartition partition =
        partition_by_ranks(o.input, o.columns, config, chunking, parts, rank, ranks, clock);
    plan.error = partition.error;
    plan.grid = partition.grid;
    plan.rows = partition.rows;
    plan.decided = partition.decided;
    plan.files = std::move(partition.files);
    store = std::move(partition.store);
  } else if (rank == 0) {  // a format read whole: rank 0 partitions alone
    try {
      io::check_mesh_output_format(o.output);
      store =
          partition_input(o.input, o.columns, config, chunking, plan.files, plan.decided, &clock);
      plan.grid = store->grid();
      plan.rows = store->rows();
    } catch (const std::exception& e) {
      plan.error = e.what();
    }
    clock.begin("join", true);  // the plan's broadcast
  }
  if (rank != 0) clock.wait("plan");
  std::vector<unsigned char> message = rank == 0 ? encode(plan) : std::vector<unsigned char>();
  broadcast_bytes(message);
  if (rank != 0) plan = decode_plan(message);
  if (!plan.error.empty()) {
    if (rank == 0) std::fprintf(stderr, "meshflow-mpi: error: %s\n", plan.error.c_str());
    return 1;
  }

  // The chunks go out from a queue on rank 0 in Morton order, each to whichever rank asks first
  // (rank 0's own graph included), so a rank with cheap chunks takes more. The weld is planned
  // over every chunk in Morton order, as in one process, so welding and orientation give the
  // same mesh for any number of ranks and any assignment.
  clock.begin("chunks", false);
  const bool in_place = finishes_in_place(config, chunking);
  const std::size_t n = plan.files.size();
  const auto chunks = static_cast<long long>(n);
  // Streamed output: each chunk's mesh waits for the weld on disk beside the chunk files (a
  // directory every rank sees), so a rank holds its chunks in flight, not all it meshed.
  const bool streamed = streams_output(o.output, config, chunking);
  const std::string spill_directory =
      n > 0 ? std::filesystem::path(plan.files.front().path).parent_path().string() : "";
  std::vector<ChunkResult> results;
  const auto collect = [&](const FramePtr& frame) {
    report.timings.insert(report.timings.end(), frame->timings.begin(), frame->timings.end());
    report.rim_trimmed += frame->rim_trimmed;  // this rank's chunks (finished in place)
    ChunkResult r;
    r.position = frame->source_index;
    if (frame->ok()) {
      r.flags = chunk_vertex_flags(*frame);
      r.mesh = std::move(frame->mesh);
      frame->mesh = TriangleMesh{};
      frame->chunk.reset();
      summarize_result(r, plan.grid.voxel_size, plan.grid.chunk_cells);
      if (streamed)
        spill_result(r, spill_directory + "/mesh_" + std::to_string(r.position) + ".bin");
    } else {
      r.error = frame->name + ": " + frame->error;
    }
    results.push_back(std::move(r));
  };
  if (rank == 0) {
    std::atomic<long long> next{0};
    const std::function<long long()> take = [&] {
      const long long p = next.fetch_add(1);
      return p < chunks ? p : -1LL;
    };
    std::exception_ptr failure;
    std::thread own([&] {
      try {
        mesh_chunk_files(plan.files, take, plan.grid, plan.rows, config, plan.decided,
                         o.chunking.in_flight, in_place, o.input, collect);
      } catch (...) {
        failure = std::current_exception();
      }
    });
    serve_chunk_queue(take, ranks);  // MPI from this (the main) thread only
    own.join();
    if (failure) std::rethrow_exception(failure);
  } else {
    bool exhausted = false;
    const std::function<long long()> ask = [&]() -> long long {
      if (exhausted) return -1;
      int request = 0;
      long long position = -1;
      MPI_Send(&request, 1, MPI_INT, 0, kRequestTag, MPI_COMM_WORLD);
      MPI_Recv(&position, 1, MPI_LONG_LONG, 0, kAnswerTag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
      exhausted = position < 0;
      return position;
    };
    mesh_chunk_files(plan.files, ask, plan.grid, plan.rows, config, plan.decided,
                     o.chunking.in_flight, in_place, o.input, collect);
  }
  clock.end();
  const double mesh_s = chunk::phase_wall(clock.phases(), "chunks");
  std::fprintf(stderr, "meshflow-mpi: rank %d/%d: %zu chunks meshed in %.2f s\n", rank, ranks,
               results.size(), mesh_s);
  // Every rank welds its own chunks (seam summaries exchanged through rank 0), then writes
  // them into the output at their rows (tools/mpi/mpi_write.h): rank 0 plans the file and
  // finishes the seams (and every rank writes its tiles). Not streamed, rank 0 gathers the
  // welded parts, concatenates them, finishes the seams and writes (and sends each rank the
  // tiles of the chunks it meshed, which it writes).
  const chunk::WeldPlan weld = weld_on_ranks(results, clock, rank, ranks, !streamed);
  report.seam_vertices = weld.merged;
  if (streamed) {
    RanksWritten written = write_on_ranks(o.output, results, weld, plan.grid, plan.rows.origin,
                                          results.size(), o.tiles, plan.files, clock, rank, ranks);
    if (rank != 0) return 0;
    for (const std::string& e : written.failed) {
      std::fprintf(stderr, "meshflow-mpi: chunk failed, its cells are missing: %s\n", e.c_str());
      report.failed.push_back(e);
    }
    if (!written.error.empty()) {
      std::fprintf(stderr, "meshflow-mpi: error: %s: %s\n",
                   (weld.triangles == 0 ? o.input : o.output).c_str(), written.error.c_str());
      return 1;
    }
    report.output_vertices = weld.vertices;
    report.output_triangles = weld.triangles;
    written.times.front().phases = clock.phases();
    written.times.front().peak_bytes = chunk::peak_resident_bytes();
    print_report(o, plan, report, written.times, written.gathered_bytes, written.tiles,
                 monotonic_seconds() - t0, limit.threads());
    return 0;
  }
  std::vector<chunk::RankTimes> times = {
      {rank, results.size(), chunk::peak_resident_bytes(), clock.phases()}};
  const ScatterJob tiling{o.tiles, plan.grid, plan.rows.origin, results.size()};
  if (rank != 0) {
    send_bytes(encode(results, times.front()), 0);
    std::vector<ChunkResult>().swap(results);
    // Every rank writes the tiles of the chunks it meshed, cut from rank 0's finished mesh.
    if (!o.tiles.empty()) scatter_tiles_to_ranks(tiling, {}, {}, "", clock, rank, ranks);
    return 0;
  }
  clock.begin("gather", true);
  std::size_t gathered_bytes = 0;
  std::map<std::array<int, 3>, int> meshed_by;  // chunk index -> the rank that meshed it
  for (int from = 1; from < ranks; ++from) {
    const std::vector<unsigned char> received = receive_bytes(from);
    gathered_bytes += received.size();
    const std::size_t before = results.size();
    times.push_back(decode_into(received, from, results));
    for (std::size_t i = before; i < results.size(); ++i) {
      const Eigen::Vector3i& c = plan.files.at(results[i].position).index;
      meshed_by[{c.x(), c.y(), c.z()}] = from;
    }
  }
  const auto owner = [&](const Eigen::Vector3i& c) {  // rank 0: its own chunks and any other
    const auto it = meshed_by.find({c.x(), c.y(), c.z()});
    return it == meshed_by.end() ? 0 : it->second;
  };
  std::sort(results.begin(), results.end(),
            [](const ChunkResult& a, const ChunkResult& b) { return a.position < b.position; });
  for (ChunkResult& r : results)
    if (!r.error.empty()) {
      std::fprintf(stderr, "meshflow-mpi: chunk failed, its cells are missing: %s\n",
                   r.error.c_str());
      report.failed.push_back(r.error);
      r = ChunkResult{};
    }
  std::size_t tiles = 0;
  {
    TriangleMesh joined;
    std::vector<std::uint8_t> flags;
    std::size_t vertices = 0, triangles = 0;
    for (const ChunkResult& r : results) {
      vertices += r.mesh.vertices.size();
      triangles += r.mesh.triangles.size();
    }
    joined.vertices.reserve(vertices);
    joined.triangles.reserve(triangles);
    for (ChunkResult& r : results) {
      chunk::append_welded(joined, r.mesh);
      flags.insert(flags.end(), r.flags.begin(), r.flags.end());
      r = ChunkResult{};
    }
    if (flags.size() != joined.vertices.size()) flags.clear();  // some chunk gave none
    clock.begin("stitch", true);  // with --finish-after-stitch: flips and rim trim
    const TriangleMesh mesh =
        finish_joined_mesh(std::move(joined), flags, config, plan.grid.voxel_size, report, {},
                           in_place, plan.grid.chunk_cells);
    if (mesh.empty()) {
      std::fprintf(stderr, "meshflow-mpi: error: %s: no surface was extracted\n", o.input.c_str());
      if (!o.tiles.empty())
        scatter_tiles_to_ranks(tiling, {}, {}, "no surface was extracted", clock, rank, ranks);
      return 1;
    }
    report.output_vertices = mesh.vertices.size();
    report.output_triangles = mesh.triangles.size();
    clock.begin("write", true);
    io::write_mesh(o.output, mesh, plan.rows.origin);
    if (!o.tiles.empty()) {  // every rank its own chunks' tiles, rank 0 the index
      const TilesWritten tiled =
          scatter_tiles_to_ranks(tiling, mesh, owner, "", clock, rank, ranks);
      for (const chunk::RankTimes& t : tiled.others) times.at(static_cast<std::size_t>(t.rank)) = t;
      if (!tiled.error.empty()) {
        std::fprintf(stderr, "meshflow-mpi: error: %s: %s\n", o.tiles.c_str(), tiled.error.c_str());
        return 1;
      }
      tiles = tiled.tiles;
    }
  }
  clock.end();
  times.front().phases = clock.phases();
  times.front().peak_bytes = chunk::peak_resident_bytes();
  print_report(o, plan, report, times, gathered_bytes, tiles, monotonic_seconds() - t0,
               limit.threads());
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
  cmd->add_option("--chunk", o->chunk,
                  "Chunk edge, metres, or \"auto\": chosen so the chunks in flight fit half of "
                  "--max-memory (1 GiB when none is given)")
      ->required()
      ->check([](const std::string& v) -> std::string {
        if (v == "auto") return "";
        try {
          std::size_t used = 0;
          const float metres = std::stof(v, &used);
          if (used == v.size() && metres > 0.0f && std::isfinite(metres)) return "";
        } catch (const std::exception&) {
        }
        return "expected \"auto\" or a positive size in metres, got \"" + v + "\"";
      });
  cmd->add_option("--chunk-overlap", o->chunking.overlap_voxels,
                  "Voxels of points each chunk sees beyond its own cells");
  cmd->add_option("--chunk-dir", o->chunking.directory,
                  "Where rank 0 writes the chunk files; every rank must see it (a shared file "
                  "system on a cluster)");
  cmd->add_option("--chunks-in-flight", o->chunking.in_flight, "Chunks meshed at once per rank");
  cmd->add_flag(
      "--finish-after-stitch{false}", o->chunking.finish_in_place,
      "Flip, trim the rim, clean and fill holes once on the stitched mesh (rank 0) instead "
      "of per chunk with seams held fixed (the single-process mesh but for a few "
      "triangles; serial, and the whole mesh several times in memory)");
  cmd->add_option("--tiles", o->tiles,
                  "Also write the mesh as one glTF file per chunk (DIR/tile_I_J_K.glb, each rank "
                  "its own chunks'), each also at coarser levels (tile_I_J_K_lodL.glb), and "
                  "their index DIR/tiles.json (and DIR/tileset.json, 3D Tiles 1.1)");
  cmd->add_flag("--json", o->json,
                "Rank 0 prints one JSON document: the mesh, and every rank's phases (wall, CPU "
                "and work seconds, peak memory) with the serial fraction they imply");
  add_pipeline_options(cmd, o->pipeline);
  cmd->callback([o, world, &status] { status = run(*o, world.rank, world.ranks); });
}

}  // namespace meshflow::cli
