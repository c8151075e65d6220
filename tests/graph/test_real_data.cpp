// End-to-end runs on the real scans in $MESHFLOW_DATA (skipped when absent).

#include <gtest/gtest.h>

#include <cstdio>

#include "graph/pipeline.h"
#include "nodes/io/read_point_cloud.h"
#include "runtime/threads.h"
#include "test_support.h"

namespace meshflow {
namespace {

void expect_plausible(const TriangleMesh& mesh, std::size_t min_tris, std::size_t max_tris) {
  EXPECT_GE(mesh.triangles.size(), min_tris);
  EXPECT_LE(mesh.triangles.size(), max_tris);
  for (const auto& v : mesh.vertices) ASSERT_TRUE(v.allFinite());
  for (const auto& n : mesh.normals) ASSERT_TRUE(n.allFinite());
  const EdgeStatistics stats = edge_statistics(mesh);
  EXPECT_EQ(stats.non_manifold_edges, 0u);
  EXPECT_EQ(stats.inconsistent_edges, 0u);
}

// File read to mesh through the graph, as `meshflow reconstruct` runs it.
FramePtr reconstruct_file(const std::string& path, const ReconstructionConfig& config) {
  auto frame = std::make_shared<Frame>();
  frame->name = path;
  frame->load = [path] { return io::read_point_cloud(path); };
  FramePtr result;
  bool given = false;
  ReconstructionPipeline(config).run(
      [&]() -> FramePtr { return given ? nullptr : (given = true, frame); },
      [&](const FramePtr& f) { result = f; });
  return result;
}

TEST(RealData, Kurt3dScan000At5cm) {
  MESHFLOW_REQUIRE_DATA("kurt3d/scan000.3d");
  ReconstructionConfig config;
  config.voxelize.voxel_size = 0.05f;
  const FramePtr result = reconstruct_file(test::data_path("kurt3d/scan000.3d"), config);
  ASSERT_TRUE(result->ok()) << result->error;
  expect_plausible(result->mesh, 60000, 250000);
  EXPECT_GT(result->filter_counts.input, 76000u);
}

TEST(RealData, Kurt3dEveryOptimizeStepKeepsTheMeshValid) {
  // The real scan's clutter (thin parts, pinches, small regions next to each other) is what
  // synthetic scenes miss: after every step the mesh stays a 2-manifold without degenerate
  // faces, and the reductions hold.
  MESHFLOW_REQUIRE_DATA("kurt3d/scan000.3d");
  ReconstructionConfig config;
  config.voxelize.voxel_size = 0.05f;
  config.optimize.steps = {OptimizeStep::kClean};
  const FramePtr result = reconstruct_file(test::data_path("kurt3d/scan000.3d"), config);
  ASSERT_TRUE(result->ok()) << result->error;
  TriangleMesh mesh = result->mesh;
  const std::size_t cleaned = mesh.triangles.size();
  for (OptimizeStep step :
       parse_optimize_steps("holes,sharpen,planes,retriangulate,remesh,decimate")) {
    SCOPED_TRACE(optimize_step_name(step));
    OptimizeConfig one_step = config.optimize;
    one_step.steps = {step};
    OptimizeReport report;
    mesh = optimize_mesh(mesh, one_step, &report);
    EXPECT_FALSE(report.steps[0].skipped) << report.steps[0].detail;
    std::printf("[ kurt3d ]%s", format_optimize_report(report).c_str());
    expect_plausible(mesh, 1000, 250000);
    for (const Triangle& t : mesh.triangles)
      ASSERT_TRUE(has_area(mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]));
    if (step == OptimizeStep::kRetriangulate) {
      EXPECT_LT(mesh.triangles.size(), cleaned / 2);
    }
  }
  EXPECT_LT(mesh.triangles.size(), cleaned / 8);
}

TEST(RealData, Kurt3dSameMeshWithOneAndTwoThreads) {
  MESHFLOW_REQUIRE_DATA("kurt3d/scan001.3d");
  ReconstructionConfig config;
  config.voxelize.voxel_size = 0.05f;
  FramePtr one, two;
  {
    ThreadLimit limit(1);
    one = reconstruct_file(test::data_path("kurt3d/scan001.3d"), config);
  }
  {
    ThreadLimit limit(2);
    two = reconstruct_file(test::data_path("kurt3d/scan001.3d"), config);
  }
  ASSERT_TRUE(one->ok() && two->ok());
  EXPECT_GT(one->mesh.triangles.size(), 10000u);
  EXPECT_EQ(one->mesh.vertices, two->mesh.vertices);
  EXPECT_EQ(one->mesh.triangles, two->mesh.triangles);
}

TEST(RealData, StanfordBunny) {
  MESHFLOW_REQUIRE_DATA("objects/bunny.pcd");
  PointCloud cloud = io::read_point_cloud(test::data_path("objects/bunny.pcd"));
  ReconstructionConfig config;
  config.normals.orientation = NormalOrientation::kAwayFromViewpoint;
  config.normals.viewpoint = finite_bounds(cloud).center();
  config.voxelize.voxel_size = 0.01f;
  config.distance.max_distance_voxels = 3.0f;
  const FramePtr f = ReconstructionPipeline(config).reconstruct(std::move(cloud), "bunny");
  ASSERT_TRUE(f->ok()) << f->error;
  expect_plausible(f->mesh, 300, 5000);
}

}  // namespace
}  // namespace meshflow
