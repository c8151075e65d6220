#include "bench_support.h"
#include "nodes/voxelize/voxelize.h"
#include "runtime/threads.h"

namespace meshflow::bench {
namespace {

void BM_Voxelize(benchmark::State& state) {
  const PointCloud* cloud = require(state, static_cast<Input>(state.range(1)));
  if (cloud == nullptr) return;
  ThreadLimit limit(static_cast<int>(state.range(0)));
  std::size_t cells = 0;
  for (auto _ : state) cells = voxelize(*cloud, VoxelizeConfig{0.05f, 0.5f}).cells.size();
  state.counters["points/s"] = benchmark::Counter(static_cast<double>(cloud->size()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
  state.counters["cells"] = static_cast<double>(cells);
}
BENCHMARK(BM_Voxelize)->Apply(thread_and_input_args);

}  // namespace
}  // namespace meshflow::bench
