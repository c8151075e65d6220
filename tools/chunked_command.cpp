// `meshflow reconstruct IN -o OUT --chunk S`: the out-of-core path (graph/chunked_reconstruction.h)
// with its report.

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "graph/chunked_reconstruction.h"
#include "nodes/chunk/phase_times.h"
#include "nodes/extract/extract_surface.h"
#include "nodes/io/mesh_writers.h"
#include "options/json_report.h"
#include "runtime/error.h"
#include "runtime/tracing.h"
#include "tools/commands.h"
#include "tools/console.h"
#include "tools/progress.h"

namespace meshflow::cli {

void run_chunked_reconstruct(const std::string& input, const std::string& columns,
                             const std::string& output, const std::string& tiles_dir,
                             const ReconstructionConfig& config, const ChunkingConfig& chunking,
                             int threads) {
  io::check_mesh_output_format(output);
  auto progress = std::make_unique<StepProgress>();
  const double t0 = monotonic_seconds();
  // Streamed to the file as the chunks are welded (the tiles: each chunk's finished rows),
  // else held whole and written (the tiles cut from it).
  const auto tell = [&](const std::string& what) { progress->begin(what); };
  ChunkedResult result =
      reconstruct_chunked_to_ply(input, columns, config, chunking, output, tiles_dir, tell);
  ChunkedReport& r = result.report;
  if (r.output_triangles == 0) {
    throw Error(input, "",
                "no surface was extracted from " + std::to_string(r.chunks) +
                    " chunks (voxel size " + std::to_string(r.voxel_size) +
                    " m too small or too large?)");
  }
  const std::size_t tiles = r.tiles;
  r.clock.end();
  progress.reset();
  const double wall = monotonic_seconds() - t0;
  // One process: its phases are the only rank's.
  const std::vector<chunk::RankTimes> ranks = {
      {0, r.chunks, chunk::peak_resident_bytes(), r.clock.phases()}};
  const chunk::SerialFraction serial = chunk::serial_fraction(ranks, wall);
  const auto phase = [&](const char* name) { return chunk::phase_wall(r.clock.phases(), name); };
  for (const std::string& failure : r.failed)
    std::fprintf(stderr, "meshflow: chunk failed, its cells are missing: %s\n", failure.c_str());
  if (console().json) {
    nlohmann::json doc = {
        {"input", input},
        {"output", output},
        {"threads", threads},
        {"wall_s", wall},
        {"voxel", r.voxel_size},  // the keys of the single-process report where they agree
        {"chunk", {{"cells", r.chunk_cells}, {"metres", r.chunk_cells * r.voxel_size}}},
        {"chunks", r.chunks},
        {"failed_chunks", r.failed},
        {"points", r.points},
        {"dropped_points", r.dropped},
        {"spilled_points", r.rows_written},
        {"max_chunk_points", r.max_chunk_points},
        {"seam_vertices", r.seam_vertices},
        {"mesh",
         {{"vertices", r.output_vertices},
          {"triangles", r.output_triangles},
          {"extract", extract_method_name(r.decided.method)}}},
        {"decided",  // once, from the whole input, for every chunk
         {{"voxel_automatic", r.decided.voxel_automatic},
          {"median_variation", r.decided.median_variation},
          {"noisy", r.decided.noisy},
          {"density", r.decided.density}}},
        {"tiles", tiles},
        {"timing", options::chunked_timing_json(ranks, wall)},
        {"optimize", options::optimize_json(r.optimize)},
        {"stages", options::stages_json(summarize_stages(r.timings))}};
    return print_json(doc);
  }
  report("input      %s: %llu points (%llu NaN/Inf dropped)\n", input.c_str(),
         static_cast<unsigned long long>(r.points), static_cast<unsigned long long>(r.dropped));
  report(
      "chunks     %zu of %d cells (%.2f m) at voxel %.4f m, extract %s; %.2fx the points "
      "spilled with overlap, at most %llu per chunk\n",
      r.chunks, r.chunk_cells, r.chunk_cells * r.voxel_size, r.voxel_size,
      extract_method_name(r.decided.method),
      static_cast<double>(r.rows_written) / static_cast<double>(r.points),
      static_cast<unsigned long long>(r.max_chunk_points));
  report("mesh       %llu vertices, %llu triangles; %zu seam vertices welded\n",
         static_cast<unsigned long long>(r.output_vertices),
         static_cast<unsigned long long>(r.output_triangles), r.seam_vertices);
  detail("%s", format_optimize_report(r.optimize).c_str());
  report(
      "time       %.1f s on %d thread%s: decide %.1f s, partition %.1f s, chunks %.1f s, "
      "stitch %.1f s, finish %.1f s, write %.1f s\n",
      wall, threads, threads == 1 ? "" : "s", phase("decide"), phase("partition"), phase("chunks"),
      phase("stitch"), phase("finish"), phase("write"));
  report("serial     %.1f s of %.1f s on one core (Amdahl: f = %.3f, at most %.1fx faster)\n",
         serial.serial_s, serial.serial_s + serial.parallel_work_s, serial.fraction,
         serial.max_speedup);
  detail("%s", format_stage_table(summarize_stages(r.timings), phase("chunks")).c_str());
  report("output     %s\n", output.c_str());
  if (tiles > 0) report("tiles      %zu in %s (tiles.json)\n", tiles, tiles_dir.c_str());
}

}  // namespace meshflow::cli
