#include "bench_support.h"
#include "nodes/normals/normals.h"
#include "runtime/threads.h"

namespace meshflow::bench {
namespace {

// kn = 10 PCA + ki = 10 interpolation over a built kd-tree, as the normals stage runs it
// (the tree is the "index" stage, shared with the distance stage; see BM_KdTreeBuild).
void BM_Normals(benchmark::State& state) {
  const PointCloud* cloud = require(state, static_cast<Input>(state.range(1)));
  if (cloud == nullptr) return;
  const Frame* f = prepared_frame(static_cast<Input>(state.range(1)), "normals");
  ThreadLimit limit(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    benchmark::DoNotOptimize(estimate_normals(f->cloud, *f->index, NormalsConfig{}).data());
  }
  state.counters["points/s"] = benchmark::Counter(static_cast<double>(cloud->size()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Normals)->Apply(thread_and_input_args);

}  // namespace
}  // namespace meshflow::bench
