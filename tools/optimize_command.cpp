// meshflow optimize IN OUT --optimize LIST: the optimisation steps on a mesh from any tool.

#include <memory>
#include <string>

#include "graph/reconstruction_config.h"
#include "nodes/io/mesh_readers.h"
#include "nodes/io/mesh_writers.h"
#include "options/json_report.h"
#include "runtime/error.h"
#include "runtime/threads.h"
#include "tools/cli_checks.h"
#include "tools/commands.h"
#include "tools/console.h"
#include "tools/pipeline_options.h"
#include "tools/progress.h"

namespace meshflow::cli {
namespace {

struct OptimizeOptions {
  std::string input, output;
  PipelineOptions pipeline;
};

void run_optimize(const OptimizeOptions& o) {
  ThreadLimit limit(o.pipeline.threads);
  io::check_mesh_output_format(o.output);
  const ReconstructionConfig config = o.pipeline.config();
  const double t0 = monotonic_seconds();
  const TriangleMesh mesh = io::read_mesh(o.input);
  if (mesh.triangles.empty()) throw Error(o.input, "face", "the file has no triangles");
  const float scale = o.pipeline.voxel > 0.0f ? o.pipeline.voxel : median_edge_length(mesh);
  OptimizeConfig optimize = optimize_config_for_voxel(config, scale);
  StepProgress progress;
  optimize.on_step = [&progress](OptimizeStep step) {
    progress.begin("optimize", optimize_step_name(step));
  };
  OptimizeReport steps;
  const TriangleMesh out = optimize_mesh(mesh, optimize, &steps);
  progress.begin("write");
  io::write_mesh(o.output, out);
  const double wall = monotonic_seconds() - t0;
  if (console().json) {
    return print_json({{"input", o.input},
                       {"output", o.output},
                       {"scale", scale},
                       {"triangles_in", mesh.triangles.size()},
                       {"vertices", out.vertices.size()},
                       {"triangles", out.triangles.size()},
                       {"optimize", options::optimize_json(steps)},
                       {"time_ms", 1e3 * wall}});
  }
  report("input      %s: %zu vertices, %zu triangles\n", o.input.c_str(), mesh.vertices.size(),
         mesh.triangles.size());
  report("scale      %.4g m (%s)\n", scale, o.pipeline.voxel > 0.0f ? "--voxel" : "median edge");
  report("optimize\n%s", format_optimize_report(steps).c_str());
  report("mesh       %zu vertices, %zu triangles\n", out.vertices.size(), out.triangles.size());
  report("time       %.1f ms on %d thread%s\n", 1e3 * wall, limit.threads(),
         limit.threads() == 1 ? "" : "s");
  report("output     %s\n", o.output.c_str());
}

}  // namespace

void add_optimize_options(CLI::App* cmd) {
  auto o = std::make_shared<OptimizeOptions>();
  cmd->add_option("input", o->input, "Mesh to optimise: .ply .obj .off .stl")->required();
  cmd->add_option("output,-o,--output", o->output, "Output mesh: .ply .obj .stl .off .glb")
      ->required();
  add_pipeline_options(cmd, o->pipeline);
  // Only the optimize settings apply here; --voxel is the scale of the voxel-relative ones.
  for (const char* unused :
       {"--kn", "--ki", "--kd", "--adaptive-k", "--max-distance", "--max-disagreement",
        "--max-extrapolation", "--max-rim", "--filter-voxel", "--outlier-k", "--min-range",
        "--max-range", "--depth-median", "--depth-bilateral", "--extract", "--normals", "--orient",
        "--organized-as-depth", "--max-memory"})
    cmd->remove_option(cmd->get_option(unused));
  for (const char* unused : {"--outlier-cluster", "--outlier-radius", "--close"})
    cmd->remove_option(cmd->get_option(unused));
  cmd->get_option("--voxel")
      ->description("Scale of the voxel-relative tolerances, metres (auto: the median edge length)")
      ->default_str("auto");
  add_console_flags(cmd, true);
  cmd->callback([o] { run_optimize(*o); });
}

}  // namespace meshflow::cli
