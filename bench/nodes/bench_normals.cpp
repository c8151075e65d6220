#include "bench_support.h"
#include "nodes/normals/normals.h"
#include "nodes/search/spatial_index.h"
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

// The same with the kd-tree built inside the timed region, as a caller with a bare cloud pays
// it (and as Open3D's EstimateNormals does, the peer of BM_Open3dNormals).
void BM_NormalsWithIndex(benchmark::State& state) {
  if (require(state, static_cast<Input>(state.range(1))) == nullptr) return;
  const PointCloud& cloud = prepared_frame(static_cast<Input>(state.range(1)), "normals")->cloud;
  ThreadLimit limit(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    const KdTreeIndex index(cloud.positions);
    benchmark::DoNotOptimize(estimate_normals(cloud, index, NormalsConfig{}).data());
  }
  state.counters["points/s"] = benchmark::Counter(static_cast<double>(cloud.size()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_NormalsWithIndex)->Apply(thread_and_input_args);

}  // namespace
}  // namespace meshflow::bench
