// Orientation by propagation and whole reconstructions of closed objects without a sensor:
// 100 000 uniform samples of the box with a through-hole (nodes/synthetic/closed_objects.h),
// no normals, voxel 1 % of the bounding-box diagonal.

#include "bench_support.h"
#include "graph/pipeline.h"
#include "nodes/filter/spatial_order.h"
#include "nodes/normals/normals.h"
#include "nodes/normals/orient_normals.h"
#include "nodes/synthetic/closed_objects.h"
#include "runtime/threads.h"

namespace meshflow::bench {
namespace {

constexpr std::size_t kObjectPoints = 100000;

const synthetic::ClosedObject& object() {
  static const synthetic::ClosedObject o = synthetic::box_with_hole_object();
  return o;
}

// The samples without normals, their neighbour table (k = 10) and unoriented plane fits.
struct OrientationInput {
  PointCloud cloud;
  NeighbourTable table;
  std::vector<Eigen::Vector3f> fitted;
  PointCloud random_order;  ///< the samples as drawn, for the whole pipeline
};

const OrientationInput& orientation_input() {
  static const OrientationInput in = [] {
    OrientationInput i;
    i.cloud = object().sample(kObjectPoints, 0.0f, 1);
    i.cloud.normals.clear();
    i.random_order = i.cloud;
    i.cloud = in_morton_order(i.cloud);  // as the index stage orders it
    const KdTreeIndex index(i.cloud.positions);
    i.table = build_neighbour_table(i.cloud.positions, index, 10);
    NormalsConfig c;
    c.orientation = NormalOrientation::kTowardViewpoint;  // any fixed sign: the input to orient
    c.ki = 0;
    i.fitted = estimate_normals(i.cloud, index, c);
    return i;
  }();
  return in;
}

// orient_by_propagation() alone: tensor-smoothed weights, spanning forest, traversal, vote,
// outward sign.
void BM_OrientNormals(benchmark::State& state) {
  const OrientationInput& in = orientation_input();
  ThreadLimit limit(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        orient_by_propagation(in.cloud.positions, in.fitted, in.table, {}, PropagationConfig{})
            .normals.data());
  }
  state.counters["points/s"] = benchmark::Counter(static_cast<double>(in.cloud.size()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_OrientNormals)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The normals stage as `reconstruct` runs it on such a cloud: neighbour table, plane fits,
// propagation, interpolation.
void BM_NormalsPropagated(benchmark::State& state) {
  const OrientationInput& in = orientation_input();
  const KdTreeIndex index(in.cloud.positions);
  ThreadLimit limit(static_cast<int>(state.range(0)));
  for (auto _ : state)
    benchmark::DoNotOptimize(compute_normals(in.cloud, index, NormalsConfig{}).normals.data());
  state.counters["points/s"] = benchmark::Counter(static_cast<double>(in.cloud.size()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_NormalsPropagated)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Read excluded (the samples in their random order): the whole pipeline from the cloud to the
// cleaned, watertight mesh.
void BM_ReconstructObject(benchmark::State& state) {
  const OrientationInput& in = orientation_input();
  ReconstructionConfig config;
  config.voxelize.voxel_size = 0.01f * object().diagonal();
  ThreadLimit limit(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    const FramePtr f = ReconstructionPipeline(config).reconstruct(in.random_order);
    if (!f->ok()) state.SkipWithError(f->error.c_str());
    benchmark::DoNotOptimize(f->mesh.triangles.data());
  }
  state.counters["points/s"] = benchmark::Counter(static_cast<double>(in.cloud.size()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_ReconstructObject)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace meshflow::bench
