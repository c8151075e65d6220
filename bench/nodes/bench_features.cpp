// The feature graph (issue 59): detection alone, and the steps that keep it (remesh, decimate)
// with it and without it (--feature-angle 180), on the cleaned 5 cm mesh. Issue 59's bar: the
// features cost at most 15 % of a step's time.

#include <map>

#include "bench_support.h"
#include "graph/pipeline.h"
#include "nodes/optimize/features.h"
#include "nodes/optimize/optimize_mesh.h"
#include "nodes/synthetic/closed_objects.h"
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
  time_optimize(state, *mesh, config);
}
BENCHMARK(BM_OptimizeWithFeatures)
    ->ArgsProduct({{1, 2}, {kSynthetic, kKurt3d}, {0, 1}, {0, 1}})
    ->ArgNames({"threads", "input", "step", "features"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// A CAD-like input besides the scans: the box with a hole (sharp edges, a cylinder) sampled
// without a sensor (100 000 points) and extracted at 1 % of its diagonal (extended marching
// cubes), as tests/graph/test_feature_preservation.cpp makes it, with the extraction's
// feature vertices (Frame::feature_vertices). Cached.
constexpr int kBoxWithHole = 9;
constexpr float kBoxWithHoleVoxelShare = 0.01f;

const Frame& box_with_hole_frame() {
  static const FramePtr frame = [] {
    const synthetic::ClosedObject object = *synthetic::closed_test_object("box-with-hole");
    ReconstructionConfig c;
    c.voxelize.voxel_size = kBoxWithHoleVoxelShare * object.diagonal();
    c.optimize.steps.clear();
    PointCloud cloud = object.sample(100000, 0.0f, 59);
    cloud.normals.clear();
    return ReconstructionPipeline(c).reconstruct(std::move(cloud));
  }();
  return *frame;
}

// A reducing list as a user runs it (reconstruct's settings at the input's voxel), with the
// feature graph (features 1: detected; 2: seeded from the extraction's feature vertices, as the
// pipeline does, where it has them) and without (0, --feature-angle 180): list 0
// clean,holes,remesh, 1 clean,holes,planes,retriangulate, 2 decimate. Input 0 the synthetic
// scan, 1 kurt3d (5 cm, raw extraction: marching cubes, no feature vertices), 9 the box with a
// hole. Issue 59's bar: features cost at most 15 %.
void BM_OptimizeChainWithFeatures(benchmark::State& state) {
  static const char* const kLists[] = {"clean,holes,remesh", "clean,holes,planes,retriangulate",
                                       "decimate"};
  const TriangleMesh* mesh = nullptr;
  const std::vector<std::uint8_t>* seed = nullptr;
  float voxel = 0.05f;
  if (state.range(1) == kBoxWithHole) {
    const Frame& frame = box_with_hole_frame();
    mesh = &frame.mesh;
    voxel = frame.voxel_size;
    seed = &frame.feature_vertices;
  } else {
    mesh = extracted_mesh(state);
  }
  if (mesh == nullptr) return;
  const int features = static_cast<int>(state.range(3));
  if (features == 2 && (seed == nullptr || seed->size() != mesh->vertices.size())) {
    state.SkipWithError("no feature vertices from the extraction");
    return;
  }
  ReconstructionConfig c;
  c.optimize.steps = parse_optimize_steps(kLists[state.range(2)]);
  c.optimize.feature_angle_deg = features > 0 ? kDefaultFeatureAngleDeg : 180.0f;
  const OptimizeConfig config = optimize_config_for_voxel(c, voxel);
  static const char* const kFeatures[] = {" no features", " features", " features seeded"};
  state.SetLabel(std::string(kLists[state.range(2)]) + kFeatures[features]);
  time_optimize(state, *mesh, config, features == 2 ? seed : nullptr);
}
BENCHMARK(BM_OptimizeChainWithFeatures)
    ->ArgsProduct({{1}, {kSynthetic, kKurt3d}, {0, 1, 2}, {0, 1}})
    ->ArgNames({"threads", "input", "list", "features"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_OptimizeChainWithFeatures)
    ->ArgsProduct({{1}, {kBoxWithHole}, {0, 1, 2}, {0, 1, 2}})
    ->ArgNames({"threads", "input", "list", "features"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace meshflow::bench
