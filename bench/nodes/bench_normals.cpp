#include "bench_support.h"
#include "nodes/normals/normals.h"
#include "runtime/threads.h"

namespace meshflow::bench {
namespace {

// kd-tree build + kn = 10 PCA + ki = 10 interpolation, as the normals stage runs it.
void BM_Normals(benchmark::State& state) {
  const PointCloud* cloud = require(state, static_cast<Input>(state.range(1)));
  if (cloud == nullptr) return;
  ThreadLimit limit(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    const KdTreeIndex index(cloud->positions);
    benchmark::DoNotOptimize(estimate_normals(*cloud, index, NormalsConfig{}).data());
  }
  state.counters["points/s"] = benchmark::Counter(static_cast<double>(cloud->size()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Normals)->Apply(thread_and_input_args);

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
