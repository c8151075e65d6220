#include <cmath>

#include "bench_support.h"
#include "nodes/optimize/cleanup/hole_filling.h"
#include "nodes/optimize/cleanup/mesh_cleanup.h"
#include "nodes/optimize/optimize_mesh.h"
#include "runtime/threads.h"

namespace meshflow::bench {
namespace {

void BM_MeshCleanup(benchmark::State& state) {
  const TriangleMesh* mesh = extracted_mesh(state);
  if (mesh == nullptr) return;
  ThreadLimit limit(static_cast<int>(state.range(0)));
  std::size_t out = 0;
  for (auto _ : state) benchmark::DoNotOptimize(out = clean_mesh(*mesh, {}).triangles.size());
  count_triangles(state, *mesh, out);
}
BENCHMARK(BM_MeshCleanup)->Apply(thread_and_input_args);

// One optimisation step alone on the cleaned mesh: 0 holes, 1 planes, 2 retriangulate,
// 3 decimate (QEM to 25 %, no depth weighting), 4 sharpen, 5 remesh (curvature-aware).
void BM_OptimizeStep(benchmark::State& state) {
  const TriangleMesh* mesh = cleaned_mesh(state);
  if (mesh == nullptr) return;
  const OptimizeStep steps[] = {OptimizeStep::kHoles,         OptimizeStep::kPlanes,
                                OptimizeStep::kRetriangulate, OptimizeStep::kDecimate,
                                OptimizeStep::kSharpen,       OptimizeStep::kRemesh};
  OptimizeConfig config;
  config.steps = {steps[state.range(2)]};
  state.SetLabel(optimize_step_name(config.steps[0]));
  time_optimize(state, *mesh, config);
  if (config.steps[0] == OptimizeStep::kDecimate)  // beside BM_MeshoptSimplify's
    count_distance_to_input(state, *mesh, optimize_mesh(*mesh, config));
}
BENCHMARK(BM_OptimizeStep)
    ->ArgsProduct({{1, 2}, {kSynthetic, kKurt3d}, {0, 1, 2, 3, 4, 5}})
    ->ArgNames({"threads", "input", "step"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The decimate step (features kept) with QemConfig::independent_collapses: passes of
// collapses whose neighbourhoods are disjoint, applied in parallel; beside BM_OptimizeStep's
// step 3 (the one-at-a-time walk) and BM_MeshoptSimplify.
void BM_OptimizeDecimateIndependent(benchmark::State& state) {
  const TriangleMesh* mesh = cleaned_mesh(state);
  if (mesh == nullptr) return;
  OptimizeConfig config;
  config.steps = {OptimizeStep::kDecimate};
  config.decimate.independent_collapses = true;
  time_optimize(state, *mesh, config);
  count_distance_to_input(state, *mesh, optimize_mesh(*mesh, config));
}
BENCHMARK(BM_OptimizeDecimateIndependent)
    ->ArgsProduct({{1, 2}, {kSynthetic, kKurt3d}})
    ->ArgNames({"threads", "input"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The decimate step (features kept, the walk) with QemConfig::walk_chunk = range(2) (0: serial
// re-evaluation; 256: the default): how the chunk trades evaluations (and the error) against
// the waits at each chunk's start, at 1 and 2 threads.
void BM_OptimizeDecimateChunk(benchmark::State& state) {
  const TriangleMesh* mesh = cleaned_mesh(state);
  if (mesh == nullptr) return;
  OptimizeConfig config;
  config.steps = {OptimizeStep::kDecimate};
  config.decimate.walk_chunk = static_cast<std::size_t>(state.range(2));
  time_optimize(state, *mesh, config);
  count_distance_to_input(state, *mesh, optimize_mesh(*mesh, config));
}
BENCHMARK(BM_OptimizeDecimateChunk)
    ->ArgsProduct({{1, 2}, {kSynthetic, kKurt3d}, {0, 256, 1024, 4096}})
    ->ArgNames({"threads", "input", "chunk"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace meshflow::bench
