#include "bench_support.h"
#include "nodes/search/spatial_index.h"

namespace meshflow::bench {
namespace {

// The FLANN kd-tree over a cloud's positions (the "index" stage, which the normals, distance
// and extract stages share). Serial.
void BM_KdTreeBuild(benchmark::State& state) {
  const PointCloud* cloud = require(state, static_cast<Input>(state.range(1)));
  if (cloud == nullptr) return;
  for (auto _ : state) benchmark::DoNotOptimize(KdTreeIndex(cloud->positions).size());
  state.counters["points/s"] = benchmark::Counter(static_cast<double>(cloud->size()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_KdTreeBuild)
    ->Args({1, kSynthetic})
    ->Args({1, kKurt3d})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace meshflow::bench
