#include <cmath>
#include <map>

#include "bench_support.h"
#include "nodes/optimize/hole_filling.h"
#include "nodes/optimize/mesh_cleanup.h"
#include "nodes/optimize/optimize_mesh.h"
#include "nodes/optimize/qem_decimation.h"
#include "nodes/optimize/region_textures.h"
#include "runtime/half_edge_mesh.h"
#include "runtime/threads.h"

#ifdef MESHFLOW_HAVE_MESHOPTIMIZER
#include <meshoptimizer.h>
#endif

namespace meshflow::bench {
namespace {

const TriangleMesh* extracted_mesh(benchmark::State& state) {
  if (require(state, static_cast<Input>(state.range(1))) == nullptr) return nullptr;
  return &prepared_frame(static_cast<Input>(state.range(1)), "optimize")->mesh;
}

// The extracted mesh after the clean step (manifold, so every step runs), cached per input.
const TriangleMesh* cleaned_mesh(benchmark::State& state) {
  static std::map<std::int64_t, TriangleMesh> cache;
  const TriangleMesh* raw = extracted_mesh(state);
  if (raw == nullptr) return nullptr;
  auto it = cache.find(state.range(1));
  if (it == cache.end()) it = cache.emplace(state.range(1), clean_mesh(*raw, {})).first;
  return &it->second;
}

void count_triangles(benchmark::State& state, const TriangleMesh& in, std::size_t out) {
  state.counters["triangles/s"] = benchmark::Counter(static_cast<double>(in.triangles.size()),
                                                     benchmark::Counter::kIsIterationInvariantRate);
  state.counters["in"] = static_cast<double>(in.triangles.size());
  state.counters["out"] = static_cast<double>(out);
}

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
  ThreadLimit limit(static_cast<int>(state.range(0)));
  std::size_t out = 0;
  for (auto _ : state)
    benchmark::DoNotOptimize(out = optimize_mesh(*mesh, config).triangles.size());
  count_triangles(state, *mesh, out);
}
BENCHMARK(BM_OptimizeStep)
    ->ArgsProduct({{1, 2}, {kSynthetic, kKurt3d}, {0, 1, 2, 3, 4, 5}})
    ->ArgNames({"threads", "input", "step"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Texture generation for the planar regions of the cleaned mesh, from the frame's points
// coloured by position (the benchmark inputs have no colours), 1 cm texels.
void BM_TexturePlanarRegions(benchmark::State& state) {
  const TriangleMesh* mesh = cleaned_mesh(state);
  if (mesh == nullptr) return;
  PointCloud points;
  points.positions =
      prepared_frame(static_cast<Input>(state.range(1)), "optimize")->cloud.positions;
  for (const Eigen::Vector3f& p : points.positions)
    points.colors.push_back(Rgb8{static_cast<std::uint8_t>(std::lround(p.x() * 40.0f) & 255),
                                 static_cast<std::uint8_t>(std::lround(p.y() * 40.0f) & 255),
                                 static_cast<std::uint8_t>(std::lround(p.z() * 40.0f) & 255)});
  const PlanarSegmentation regions = grow_planar_regions(HalfEdgeMesh(*mesh));
  ThreadLimit limit(static_cast<int>(state.range(0)));
  std::size_t textures = 0;
  for (auto _ : state)
    benchmark::DoNotOptimize(textures =
                                 texture_planar_regions(*mesh, regions, points).textures.size());
  state.counters["textures"] = static_cast<double>(textures);
}
BENCHMARK(BM_TexturePlanarRegions)->Apply(thread_and_input_args);

#ifdef MESHFLOW_HAVE_MESHOPTIMIZER
// The reference: meshoptimizer's simplifier (edge collapses with quadrics, single-threaded) to
// 25 % of the triangles, no error limit, on the same mesh.
void BM_MeshoptSimplify(benchmark::State& state) {
  const TriangleMesh* mesh = cleaned_mesh(state);
  if (mesh == nullptr) return;
  const std::size_t indices = mesh->triangles.size() * 3;
  std::vector<unsigned int> out(indices);
  std::size_t kept = 0;
  for (auto _ : state) {
    kept = meshopt_simplify(out.data(), mesh->triangles.front().data(), indices,
                            mesh->vertices.front().data(), mesh->vertices.size(),
                            sizeof(Eigen::Vector3f), indices / 4, 1.0f, 0, nullptr);
    benchmark::DoNotOptimize(out.data());
  }
  count_triangles(state, *mesh, kept / 3);
}
BENCHMARK(BM_MeshoptSimplify)
    ->ArgsProduct({{1}, {kSynthetic, kKurt3d}})
    ->ArgNames({"threads", "input"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
#endif

}  // namespace
}  // namespace meshflow::bench
