// `meshflow reconstruct IN -o OUT --chunk S`: the out-of-core path (graph/chunked_reconstruction.h)
// with its report.

#include <cstdio>
#include <memory>
#include <string>

#include "graph/chunked_reconstruction.h"
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
                             const std::string& output, const ReconstructionConfig& config,
                             const ChunkingConfig& chunking, int threads) {
  io::check_mesh_output_format(output);
  auto progress = std::make_unique<StepProgress>();
  const double t0 = monotonic_seconds();
  ChunkedResult result = reconstruct_chunked(
      input, columns, config, chunking, [&](const std::string& what) { progress->begin(what); });
  const ChunkedReport& r = result.report;
  if (result.mesh.empty()) {
    throw Error(input, "",
                "no surface was extracted from " + std::to_string(r.chunks) +
                    " chunks (voxel size " + std::to_string(r.voxel_size) +
                    " m too small or too large?)");
  }
  progress->begin("write");
  io::write_mesh(output, result.mesh, result.origin);
  progress.reset();
  const double wall = monotonic_seconds() - t0;
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
         {{"vertices", result.mesh.vertices.size()},
          {"triangles", result.mesh.triangles.size()},
          {"extract", extract_method_name(r.decided.method)}}},
        {"decided",  // once, from the whole input, for every chunk
         {{"voxel_automatic", r.decided.voxel_automatic},
          {"median_variation", r.decided.median_variation},
          {"noisy", r.decided.noisy}}},
        {"phases_s",
         {{"partition", r.partition_s},
          {"mesh", r.mesh_s},
          {"stitch", r.stitch_s},
          {"optimize", r.optimize_s}}},
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
  report("mesh       %zu vertices, %zu triangles; %zu seam vertices welded\n",
         result.mesh.vertices.size(), result.mesh.triangles.size(), r.seam_vertices);
  detail("%s", format_optimize_report(r.optimize).c_str());
  report(
      "time       %.1f s on %d thread%s: partition %.1f s, chunks %.1f s, stitch %.1f s, "
      "optimize %.1f s\n",
      wall, threads, threads == 1 ? "" : "s", r.partition_s, r.mesh_s, r.stitch_s, r.optimize_s);
  detail("%s", format_stage_table(summarize_stages(r.timings), r.mesh_s).c_str());
  report("output     %s\n", output.c_str());
}

}  // namespace meshflow::cli
