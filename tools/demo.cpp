// `meshflow demo`: scans a synthetic room with a simulated laser scanner, reconstructs it and
// reports speed and accuracy against the analytic scene. Needs no input files.

#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "graph/pipeline.h"
#include "nodes/io/mesh_writers.h"
#include "nodes/synthetic/scan_simulator.h"
#include "runtime/threads.h"
#include "tools/cli_checks.h"
#include "tools/commands.h"
#include "tools/console.h"
#include "tools/report.h"

namespace meshflow::cli {
namespace {

struct DemoOptions {
  std::string output = "meshflow_demo.ply";
  float voxel = 0.05f;
  float noise = 0.002f;
  int threads = 0;
};

void run_demo(const DemoOptions& o) {
  ThreadLimit limit(o.threads);
  const synthetic::Scene scene = synthetic::demo_room_scene();
  synthetic::ScanConfig scan;
  scan.noise_sigma = o.noise;
  report(
      "demo       simulated laser scan of an 8 x 6 x 3 m room with a block, a cabinet and a "
      "ball\n");
  report("           %d x %d rays from (%.1f, %.1f, %.1f) m, range noise %.1f mm\n",
         scan.azimuth_steps, scan.elevation_steps, scan.origin.x(), scan.origin.y(),
         scan.origin.z(), 1e3 * o.noise);
  PointCloud cloud = synthetic::simulate_scan(scene, scan);

  ReconstructionConfig config;
  config.voxelize.voxel_size = o.voxel;
  ReconstructionPipeline pipeline(config, 1);
  const double t0 = monotonic_seconds();
  const FramePtr frame = pipeline.reconstruct(std::move(cloud), "synthetic room scan");
  const double wall = monotonic_seconds() - t0;
  throw_if_failed(*frame);
  io::write_mesh(o.output, frame->mesh);
  print_frame_report(*frame, wall, limit.threads());

  std::vector<float> errors(frame->mesh.vertices.size());
  for (std::size_t i = 0; i < errors.size(); ++i) {
    errors[i] = synthetic::surface_distance(scene, frame->mesh.vertices[i]);
  }
  std::sort(errors.begin(), errors.end());
  double sum = 0.0;
  for (float e : errors) sum += e;
  if (!errors.empty()) {
    const double mean = sum / static_cast<double>(errors.size());
    const float p95 = errors[errors.size() * 95 / 100];
    report(
        "accuracy   vertex-to-true-surface distance: mean %.2f mm (%.3f voxel), p95 %.2f mm, max "
        "%.2f mm\n",
        1e3 * mean, mean / o.voxel, 1e3 * p95, 1e3 * errors.back());
  }
  report("throughput %.2f M points/s\n",
         static_cast<double>(frame->filter_counts.input) / wall * 1e-6);
  report("output     %s\n", o.output.c_str());
}

}  // namespace

void add_demo_options(CLI::App* cmd) {
  auto opts = std::make_shared<DemoOptions>();
  cmd->add_option("-o,--output", opts->output, "Output mesh (.ply or .obj)");
  cmd->add_option("--voxel", opts->voxel, "Voxel size in metres")->check(number_in(0, 1000, true));
  cmd->add_option("--noise", opts->noise, "Range noise of the simulated scanner, metres")
      ->check(number_in(0, 1));
  cmd->add_option("--threads", opts->threads, "Worker threads (0: all cores)")
      ->check(CLI::Range(0, 1024))
      ->default_str("all cores");
  add_console_flags(cmd, false);
  cmd->callback([opts] { run_demo(*opts); });
}

}  // namespace meshflow::cli
