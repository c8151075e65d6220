// Per-frame depth-map triangulation of a 640 x 480 frame (the first Redwood frame when present,
// else a synthetic frame of the demo room): depth filter with occlusion edges, back-projection,
// triangulation and compaction into a mesh, as one call; and the same for an organized Kinect
// cloud, with the test that recognises such a cloud as a depth image; and the per-frame metrics.

#include <fstream>

#include "bench_support.h"
#include "nodes/depth/organized_depth.h"
#include "nodes/eval/completeness.h"
#include "nodes/io/read_point_cloud.h"
#include "nodes/triangulate/depth_noise.h"
#include "nodes/triangulate/depth_triangulation.h"
#include "runtime/threads.h"

namespace meshflow::bench {
namespace {

// Args: threads, input (1 = Redwood, 0 = synthetic), method (0 = naive, 1 = restricted quadtree,
// 2 = restricted quadtree then QEM decimation to 25 %, 3 / 4 = 1 / 2 after a 5 x 5 median).
void BM_TriangulateDepth(benchmark::State& state) {
  const bool redwood = state.range(1) == 1;
  const std::vector<DepthFrame>* frames = require_depth_frames(state, redwood);
  if (frames == nullptr) return;
  DepthTriangulationConfig config;
  config.method = state.range(2) >= 1 ? DepthTriangulationMethod::kRestrictedQuadtree
                                      : DepthTriangulationMethod::kNaive;
  if (state.range(2) == 2 || state.range(2) == 4) config.decimate_to = 0.25f;
  if (state.range(2) >= 3) config.filter.median_kernel = 5;
  const char* names[] = {"naive", "rqt", "rqt+qem25%", "median5+rqt", "median5+rqt+qem25%"};
  state.SetLabel(std::string(redwood ? "redwood " : "synthetic ") + names[state.range(2)]);
  ThreadLimit limit(static_cast<int>(state.range(0)));
  std::size_t triangles = 0;
  for (auto _ : state) triangles = triangulate_depth(frames->front(), config).triangles.size();
  state.counters["triangles"] = static_cast<double>(triangles);
}
BENCHMARK(BM_TriangulateDepth)
    ->ArgNames({"threads", "redwood", "method"})
    ->ArgsProduct({{1, 2}, {0, 1}, {0, 1, 2, 3, 4}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The per-frame noise estimate behind the quadtree's threshold. Args: threads, input (1 =
// Redwood, 0 = synthetic).
void BM_DepthNoiseEstimate(benchmark::State& state) {
  const bool redwood = state.range(1) == 1;
  const std::vector<DepthFrame>* frames = require_depth_frames(state, redwood);
  if (frames == nullptr) return;
  const PointGrid grid = grid_from_depth(frames->front(), DepthFilterConfig{});
  ThreadLimit limit(static_cast<int>(state.range(0)));
  float noise = 0.0f;
  for (auto _ : state) benchmark::DoNotOptimize(noise = estimate_noise_per_depth2(grid));
  state.counters["noise_per_depth2"] = static_cast<double>(noise);
  state.SetLabel(redwood ? "redwood" : "synthetic");
}
BENCHMARK(BM_DepthNoiseEstimate)
    ->ArgNames({"threads", "redwood"})
    ->ArgsProduct({{1, 2}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// An organized Kinect PCD frame (kinect_pcl/office1.pcd): recognising it as a pinhole depth
// image (depth_frame_from_organized, serial), or triangulating it as its pixel grid (RQT, then
// QEM to 25 %). Args: threads, what (0 = depth image, 1 = rqt, 2 = rqt + qem 25 %).
void BM_OrganizedCloud(benchmark::State& state) {
  static const PointCloud* cloud = [] {
    const std::string path = data_dir() + "/kinect_pcl/office1.pcd";
    return std::ifstream(path) ? new PointCloud(io::read_point_cloud(path)) : nullptr;
  }();
  if (cloud == nullptr) {
    state.SkipWithError(("kinect_pcl/office1.pcd not found in " + data_dir()).c_str());
    return;
  }
  const char* names[] = {"depth image", "rqt", "rqt+qem25%"};
  state.SetLabel(names[state.range(1)]);
  DepthTriangulationConfig config;
  config.method = DepthTriangulationMethod::kRestrictedQuadtree;
  if (state.range(1) == 2) config.decimate_to = 0.25f;
  ThreadLimit limit(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    if (state.range(1) == 0)
      benchmark::DoNotOptimize(depth_frame_from_organized(*cloud).has_value());
    else
      benchmark::DoNotOptimize(triangulate_organized(*cloud, config).triangles.size());
  }
}
BENCHMARK(BM_OrganizedCloud)
    ->ArgNames({"threads", "what"})
    ->ArgsProduct({{1, 2}, {0, 1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The per-frame metrics (nodes/eval/completeness.h) on the synthetic 640 x 480 frame: RQT +
// QEM 25 % (5 868 triangles) against the naive mesh (609 463 triangles). Args: threads, metric
// (0 = completeness: a ray per pixel into both meshes, 1 = symmetric Hausdorff distance).
void BM_TriangulationMetrics(benchmark::State& state) {
  const DepthFrame& frame = depth_frames(false).front();
  static const TriangleMesh naive = triangulate_depth(frame);
  static const TriangleMesh decimated = [&frame] {
    DepthTriangulationConfig config;
    config.method = DepthTriangulationMethod::kRestrictedQuadtree;
    config.decimate_to = 0.25f;
    return triangulate_depth(frame, config);
  }();
  const bool hausdorff = state.range(1) == 1;
  state.SetLabel(hausdorff ? "hausdorff rqt+qem25% vs naive" : "completeness rqt+qem25% vs naive");
  ThreadLimit limit(static_cast<int>(state.range(0)));
  double value = 0.0;
  for (auto _ : state)
    benchmark::DoNotOptimize(
        value =
            hausdorff
                ? hausdorff_distance(decimated, naive)
                : completeness(decimated, naive, frame.intrinsics, frame.T_world_camera).kept());
  // (Google Benchmark prints 0.0057 as "5.7m", milli: the distance is reported in mm.)
  state.counters[hausdorff ? "hausdorff_mm" : "h_n"] = hausdorff ? 1000.0 * value : value;
}
BENCHMARK(BM_TriangulationMetrics)
    ->ArgNames({"threads", "metric"})
    ->ArgsProduct({{1, 2}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace meshflow::bench
