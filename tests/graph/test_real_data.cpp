// End-to-end runs on the real scans in $MESHFLOW_DATA (skipped when absent).

#include <gtest/gtest.h>

#include "graph/pipeline.h"
#include "nodes/io/read_point_cloud.h"
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

TEST(RealData, Kurt3dScan000At5cm) {
  MESHFLOW_REQUIRE_DATA("kurt3d/scan000.3d");
  ReconstructionConfig config;
  config.voxelize.voxel_size = 0.05f;
  auto frame = std::make_shared<Frame>();
  const std::string path = test::data_path("kurt3d/scan000.3d");
  frame->load = [path] { return io::read_point_cloud(path); };
  FramePtr result;
  bool given = false;
  ReconstructionPipeline(config).run(
      [&]() -> FramePtr { return given ? nullptr : (given = true, frame); },
      [&](const FramePtr& f) { result = f; });
  ASSERT_TRUE(result->ok()) << result->error;
  expect_plausible(result->mesh, 60000, 250000);
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
