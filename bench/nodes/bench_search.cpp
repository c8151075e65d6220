#include "bench_support.h"
#include "nodes/search/neighbour_table.h"
#include "nodes/search/spatial_index.h"
#include "runtime/threads.h"

namespace meshflow::bench {
namespace {

// The kd-tree over a cloud's positions (the "index" stage, which the normals, distance and
// extract stages share). Parallel over subtrees.
void BM_KdTreeBuild(benchmark::State& state) {
  const PointCloud* cloud = require(state, static_cast<Input>(state.range(1)));
  if (cloud == nullptr) return;
  ThreadLimit limit(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(KdTreeIndex(cloud->positions).size());
  state.counters["points/s"] = benchmark::Counter(static_cast<double>(cloud->size()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_KdTreeBuild)->Apply(thread_and_input_args);

// The k = 10 nearest neighbours of every point of the cloud (the table the normals stage
// shares between plane fits, orientation and interpolation), over a built tree.
void BM_NeighbourTable(benchmark::State& state) {
  const PointCloud* cloud = require(state, static_cast<Input>(state.range(1)));
  if (cloud == nullptr) return;
  const KdTreeIndex index(cloud->positions);
  ThreadLimit limit(static_cast<int>(state.range(0)));
  for (auto _ : state)
    benchmark::DoNotOptimize(build_neighbour_table(cloud->positions, index, 10).indices.data());
  state.counters["points/s"] = benchmark::Counter(static_cast<double>(cloud->size()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_NeighbourTable)->Apply(thread_and_input_args);

// Single k = 10 queries one after another, each 1 mm off a point of the cloud (in the cloud's
// order): the path of the distance stage and of the filters.
void BM_KnnQueries(benchmark::State& state) {
  const PointCloud* cloud = require(state, static_cast<Input>(state.range(1)));
  if (cloud == nullptr) return;
  const KdTreeIndex index(cloud->positions);
  const Eigen::Vector3f offset(1e-3f, 1e-3f, 1e-3f);
  std::uint32_t idx[10];
  float d2[10];
  for (auto _ : state)
    for (const Eigen::Vector3f& p : cloud->positions)
      benchmark::DoNotOptimize(index.knn(p + offset, 10, idx, d2));
  state.counters["queries/s"] = benchmark::Counter(static_cast<double>(cloud->size()),
                                                   benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_KnnQueries)
    ->ArgsProduct({{1}, {kSynthetic, kKurt3d}})
    ->ArgNames({"threads", "input"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace meshflow::bench
