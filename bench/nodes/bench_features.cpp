// The feature graph (issue 59): detection alone, and the steps that keep it (remesh, decimate)
// with it and without it (--feature-angle 180), on the cleaned 5 cm mesh. Issue 59's bar: the
// features cost at most 15 % of a step's time.

#include "bench_support.h"
#include "nodes/optimize/features.h"
#include "nodes/optimize/optimize_mesh.h"
#include "runtime/threads.h"

namespace meshflow::bench {
namespace {

void BM_DetectFeatures(benchmark::State& state) {
  const TriangleMesh* mesh = cleaned_mesh(state);
  if (mesh == nullptr) return;
  ThreadLimit limit(static_cast<int>(state.range(0)));
  MeshFeatures f;
  for (auto _ : state) benchmark::DoNotOptimize(f = detect_features(*mesh));
  count_triangles(state, *mesh, mesh->triangles.size());
  state.counters["sharp_edges"] = static_cast<double>(f.edges.size());
  state.counters["corners"] = static_cast<double>(f.count(MeshFeatures::VertexKind::kCorner));
}
BENCHMARK(BM_DetectFeatures)->Apply(thread_and_input_args);

// step 0 remesh, 1 decimate; features 0: --feature-angle 180 (none), 1: the default 40.
void BM_OptimizeWithFeatures(benchmark::State& state) {
  const TriangleMesh* mesh = cleaned_mesh(state);
  if (mesh == nullptr) return;
  OptimizeConfig config;
  config.steps = {state.range(2) == 0 ? OptimizeStep::kRemesh : OptimizeStep::kDecimate};
  config.feature_angle_deg = state.range(3) == 1 ? kDefaultFeatureAngleDeg : 180.0f;
  state.SetLabel(std::string(optimize_step_name(config.steps[0])) +
                 (state.range(3) == 1 ? " features" : " no features"));
  ThreadLimit limit(static_cast<int>(state.range(0)));
  std::size_t out = 0;
  for (auto _ : state)
    benchmark::DoNotOptimize(out = optimize_mesh(*mesh, config).triangles.size());
  count_triangles(state, *mesh, out);
}
BENCHMARK(BM_OptimizeWithFeatures)
    ->ArgsProduct({{1, 2}, {kSynthetic, kKurt3d}, {0, 1}, {0, 1}})
    ->ArgNames({"threads", "input", "step", "features"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace meshflow::bench
