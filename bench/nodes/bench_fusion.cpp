// TSDF fusion: integration of 640 x 480 depth frames (the 5 Redwood frames when present, else
// 5 synthetic frames of the demo room) at 1 cm and 5 mm, and extraction of the fused mesh.

#include "bench_support.h"
#include "nodes/fusion/tsdf_mesher.h"
#include "nodes/fusion/tsdf_volume.h"
#include "runtime/threads.h"

namespace meshflow::bench {
namespace {

// Args: threads, voxel in 0.1 mm, input (1 = Redwood, 0 = synthetic), integrator (0 =
// projective, 1 = along rays).
void BM_TsdfIntegrate(benchmark::State& state) {
  const std::vector<DepthFrame>* frames = require_depth_frames(state, state.range(2) == 1);
  if (frames == nullptr) return;
  const std::vector<DepthFrame>& input = *frames;
  ThreadLimit limit(static_cast<int>(state.range(0)));
  const float voxel = static_cast<float>(state.range(1)) * 1e-4f;
  std::size_t voxels = 0, blocks = 0;
  for (auto _ : state) {
    state.PauseTiming();
    TsdfConfig config{voxel};
    config.integrator =
        state.range(3) == 1 ? TsdfIntegrator::kAlongRay : TsdfIntegrator::kProjective;
    TsdfVolume volume(config);
    voxels = 0;
    state.ResumeTiming();
    for (const DepthFrame& f : input) voxels += volume.integrate(f).voxels_updated;
    blocks = volume.block_count();
  }
  const auto n = static_cast<double>(input.size());
  state.counters["frames/s"] = benchmark::Counter(n, benchmark::Counter::kIsIterationInvariantRate);
  // Inverted rate of n / 1000 frames per second: seconds per 1000 frames, i.e. ms per frame.
  state.counters["ms/frame"] = benchmark::Counter(
      n * 1e-3, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["voxels/s"] = benchmark::Counter(static_cast<double>(voxels),
                                                  benchmark::Counter::kIsIterationInvariantRate);
  state.counters["blocks"] = static_cast<double>(blocks);
}
BENCHMARK(BM_TsdfIntegrate)
    ->ArgNames({"threads", "voxel_0.1mm", "redwood", "along_ray"})
    ->ArgsProduct({{1, 2}, {100, 50}, {1, 0}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_TsdfExtract(benchmark::State& state) {
  const std::vector<DepthFrame>* frames = require_depth_frames(state, state.range(2) == 1);
  if (frames == nullptr) return;
  const std::vector<DepthFrame>& input = *frames;
  TsdfVolume volume(TsdfConfig{static_cast<float>(state.range(1)) * 1e-4f});
  for (const DepthFrame& f : input) volume.integrate(f);
  ThreadLimit limit(static_cast<int>(state.range(0)));
  std::size_t triangles = 0;
  for (auto _ : state) triangles = TsdfMesher().extract(volume).triangles.size();
  state.counters["triangles"] = static_cast<double>(triangles);
  state.counters["blocks/s"] = benchmark::Counter(static_cast<double>(volume.block_count()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_TsdfExtract)
    ->ArgNames({"threads", "voxel_0.1mm", "redwood"})
    ->ArgsProduct({{1, 2}, {100, 50}, {1, 0}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace meshflow::bench
