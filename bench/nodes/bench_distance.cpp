#include "bench_support.h"
#include "nodes/distance/hoppe_distance.h"
#include "runtime/threads.h"

namespace meshflow::bench {
namespace {

void BM_HoppeDistance(benchmark::State& state) {
  if (require(state, static_cast<Input>(state.range(1))) == nullptr) return;
  const Frame* f = prepared_frame(static_cast<Input>(state.range(1)), "distance");
  ThreadLimit limit(static_cast<int>(state.range(0)));
  for (auto _ : state)
    benchmark::DoNotOptimize(
        hoppe_distance(f->grid, f->cloud, *f->index, DistanceConfig{}).values.data());
  state.counters["corners/s"] = benchmark::Counter(static_cast<double>(f->grid.corners.size()),
                                                   benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_HoppeDistance)->Apply(thread_and_input_args);

}  // namespace
}  // namespace meshflow::bench
