#include "bench_support.h"
#include "nodes/filter/filter.h"
#include "runtime/threads.h"

namespace meshflow::bench {
namespace {

void BM_FilterVoxelGridAndOutliers(benchmark::State& state) {
  const PointCloud* cloud = require(state, static_cast<Input>(state.range(1)));
  if (cloud == nullptr) return;
  ThreadLimit limit(static_cast<int>(state.range(0)));
  FilterConfig config;
  config.voxel_size = 0.02f;
  config.outlier_k = 8;
  for (auto _ : state) benchmark::DoNotOptimize(filter_cloud(*cloud, config).size());
  state.counters["points/s"] = benchmark::Counter(static_cast<double>(cloud->size()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_FilterVoxelGridAndOutliers)->Apply(thread_and_input_args);

}  // namespace
}  // namespace meshflow::bench
