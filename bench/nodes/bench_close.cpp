// The close stage (--close) on a synthetic object scan: the torus seen from eight views on one
// ring (its underside and inner top unseen), 0.5 % outliers, 1 % of the diagonal voxels: the
// distance field the close stage fills, solved as one lattice ("dense") and as a coarse
// lattice plus tiles of 32 cells ("tiled", the path of lattices over max_dense_corners); and
// the whole pipeline on that scan, open and with --close (the time bar: --close at most
// twice the open run), on 1 and 2 threads.

#include <memory>
#include <string>

#include "bench_support.h"
#include "graph/pipeline.h"
#include "graph/stages.h"
#include "nodes/close/close_surface.h"
#include "nodes/synthetic/closed_objects.h"
#include "nodes/synthetic/object_scan.h"
#include "runtime/threads.h"

namespace meshflow::bench {
namespace {

// The torus seen from eight views with 0.5 % outliers, and the pipeline's config for it
// (voxels of 1 % of the diagonal). Cached.
const PointCloud& close_bench_scan() {
  static const PointCloud cloud = [] {
    synthetic::ObjectScanConfig scan;
    scan.outlier_fraction = 0.005f;
    return synthetic::scan_object(*synthetic::closed_test_object("torus"), scan).cloud;
  }();
  return cloud;
}

ReconstructionConfig close_bench_config() {
  ReconstructionConfig config;
  config.voxelize.voxel_size = 0.01f * synthetic::closed_test_object("torus")->diagonal();
  return config;
}

// The scan advanced through the stages up to the close stage. Cached.
const Frame& close_bench_frame() {
  static const std::unique_ptr<Frame> frame = [] {
    const ReconstructionConfig config = close_bench_config();
    auto f = std::make_unique<Frame>();
    f->cloud = close_bench_scan();
    for (const stages::NamedStage& s : stages::kPointCloudStages) {
      if (std::string(s.name) == "extract") break;
      stages::run_stage(s.name, s.body, *f, config);
    }
    return f;
  }();
  return *frame;
}

void BM_CloseDistanceField(benchmark::State& state) {
  const Frame& f = close_bench_frame();
  CloseConfig config;
  if (state.range(1) == 1) {  // tiled: a coarse lattice of every 4th corner, tiles of 32 cells
    config.max_dense_corners = std::size_t{1} << 16;
    config.tile_cells = 32;
  }
  ThreadLimit limit(static_cast<int>(state.range(0)));
  CloseReport report;
  for (auto _ : state)
    benchmark::DoNotOptimize(
        close_distance_field(f.grid, f.distance, f.cloud, config, &report).distance.values.data());
  const double lattice =
      static_cast<double>(report.lattice.x()) * report.lattice.y() * report.lattice.z();
  state.counters["lattice"] = lattice;
  state.counters["tiles"] = static_cast<double>(report.tiles);
  state.counters["corners/s"] =
      benchmark::Counter(lattice, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_CloseDistanceField)
    ->ArgNames({"threads", "tiled"})
    ->Args({1, 0})
    ->Args({2, 0})
    ->Args({1, 1})
    ->Args({2, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The whole pipeline from the scan to the mesh, open (close = 0) or with --close (1).
void BM_CloseScanPipeline(benchmark::State& state) {
  ReconstructionConfig config = close_bench_config();
  config.close.enabled = state.range(1) == 1;
  ThreadLimit limit(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    const FramePtr f = ReconstructionPipeline(config).reconstruct(close_bench_scan());
    if (!f->ok()) state.SkipWithError(f->error.c_str());
    benchmark::DoNotOptimize(f->mesh.triangles.data());
  }
  state.counters["points/s"] = benchmark::Counter(static_cast<double>(close_bench_scan().size()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_CloseScanPipeline)
    ->ArgNames({"threads", "close"})
    ->Args({1, 0})
    ->Args({1, 1})
    ->Args({2, 0})
    ->Args({2, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace meshflow::bench
