// The depth-frame kernels on one synthetic 640 x 480 frame of the demo room, 1 cm voxels.

#include "bench_support.h"
#include "nodes/depth/depth_filter.h"
#include "nodes/depth/depth_smoothing.h"
#include "nodes/distance/projective_distance.h"
#include "nodes/normals/organized_normals.h"
#include "nodes/synthetic/depth_sequence.h"
#include "nodes/voxelize/voxelize.h"
#include "runtime/threads.h"

namespace meshflow::bench {
namespace {

const DepthFrame& room_frame() {
  static const DepthFrame frame = [] {
    const synthetic::Scene scene = synthetic::demo_room_scene();
    const Eigen::Vector3f eye = scene.room.center;
    return synthetic::render_depth(scene, PinholeIntrinsics{},
                                   synthetic::look_at(eye, eye + Eigen::Vector3f(1, 0.3f, -0.35f)),
                                   0.001f);
  }();
  return frame;
}

// The frame's filtered depth, back-projected, finite points only (what voxelize receives).
const PointCloud& room_cloud() {
  static const PointCloud cloud = [] {
    const PointCloud organized =
        back_project(room_frame(), filter_depth(room_frame(), DepthFilterConfig{}));
    PointCloud finite;
    for (const auto& p : organized.positions) {
      if (p.allFinite()) finite.positions.push_back(p);
    }
    return finite;
  }();
  return cloud;
}

void BM_DepthFilter(benchmark::State& state) {
  ThreadLimit limit(static_cast<int>(state.range(0)));
  for (auto _ : state)
    benchmark::DoNotOptimize(filter_depth(room_frame(), DepthFilterConfig{}).data());
  state.counters["pixels/s"] =
      benchmark::Counter(640.0 * 480.0, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_DepthFilter)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The optional smoothing filters (DepthFilterConfig::median_kernel, bilateral_sigma_depth) on
// the frame in metres; args: filter (0 = median 5x5, 1 = bilateral, sigma 1 cm), threads.
void BM_DepthSmoothing(benchmark::State& state) {
  const Image depth = depth_in_metres(room_frame());
  const bool median = state.range(0) == 0;
  ThreadLimit limit(static_cast<int>(state.range(1)));
  for (auto _ : state) {
    const Image out = median ? median_filter_depth(depth, 5) : bilateral_filter_depth(depth, 0.01f);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetLabel(median ? "median 5x5" : "bilateral 5x5");
  state.counters["pixels/s"] =
      benchmark::Counter(640.0 * 480.0, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_DepthSmoothing)
    ->ArgNames({"filter", "threads"})
    ->ArgsProduct({{0, 1}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_BackProject(benchmark::State& state) {
  const Image depth = filter_depth(room_frame(), DepthFilterConfig{});
  ThreadLimit limit(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(back_project(room_frame(), depth).size());
  state.counters["pixels/s"] =
      benchmark::Counter(640.0 * 480.0, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_BackProject)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_BackProjectValid(benchmark::State& state) {
  const Image depth = filter_depth(room_frame(), DepthFilterConfig{});
  ThreadLimit limit(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(back_project_valid(room_frame(), depth).size());
  state.counters["pixels/s"] =
      benchmark::Counter(640.0 * 480.0, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_BackProjectValid)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_VoxelizeDepthFrame(benchmark::State& state) {
  ThreadLimit limit(static_cast<int>(state.range(0)));
  std::size_t cells = 0;
  for (auto _ : state) cells = voxelize(room_cloud(), VoxelizeConfig{0.01f, 0.5f}).cells.size();
  state.counters["points/s"] = benchmark::Counter(static_cast<double>(room_cloud().size()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
  state.counters["cells"] = static_cast<double>(cells);
}
BENCHMARK(BM_VoxelizeDepthFrame)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_ProjectiveDistance(benchmark::State& state) {
  const Image depth = filter_depth(room_frame(), DepthFilterConfig{});
  const SparseGrid grid = voxelize(room_cloud(), VoxelizeConfig{0.01f, 0.5f});
  ThreadLimit limit(static_cast<int>(state.range(0)));
  const DepthFrame& f = room_frame();
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        projective_distance(grid, depth, f.intrinsics, f.T_world_camera).values.data());
  }
  state.counters["corners/s"] = benchmark::Counter(static_cast<double>(grid.corners.size()),
                                                   benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_ProjectiveDistance)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace meshflow::bench
