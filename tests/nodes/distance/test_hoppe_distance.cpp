#include "nodes/distance/hoppe_distance.h"

#include <gtest/gtest.h>

#include "nodes/synthetic/shapes.h"
#include "runtime/error.h"

namespace meshflow {
namespace {

TEST(HoppeDistance, ExactOnAPlaneWithExactNormals) {
  PointCloud c;
  for (int i = -20; i <= 20; ++i)
    for (int j = -20; j <= 20; ++j) {
      c.positions.emplace_back(0.01f * i, 0.01f * j, 0.013f);
      c.normals.emplace_back(0, 0, 1);
    }
  const KdTreeIndex index(c.positions);
  const SparseGrid grid = voxelize(c, VoxelizeConfig{0.02f, 0.5f});
  const DistanceField field = hoppe_distance(grid, c, index, DistanceConfig{});
  std::size_t checked = 0;
  for (std::size_t i = 0; i < grid.corners.size(); ++i) {
    if (!field.valid[i]) continue;
    EXPECT_NEAR(field.values[i], grid.corner_position(i).z() - 0.013f, 1e-5f);
    ++checked;
  }
  EXPECT_GT(checked, 1000u);
}

TEST(HoppeDistance, ACloudWithoutOneNormalPerPointIsAnError) {
  PointCloud c;
  for (int i = 0; i < 10; ++i) c.positions.emplace_back(0.01f * i, 0.0f, 0.0f);
  const KdTreeIndex index(c.positions);
  const SparseGrid grid = voxelize(c, VoxelizeConfig{0.02f, 0.5f});
  EXPECT_THROW(hoppe_distance(grid, c, index, DistanceConfig{}), Error);
  c.normals.assign(5, Eigen::Vector3f::UnitZ());
  EXPECT_THROW(hoppe_distance(grid, c, index, DistanceConfig{}), Error);
}

TEST(HoppeDistance, NearTheTrueSignedDistanceOfASphereAndInvalidFarAway) {
  const synthetic::Sphere sphere{{0, 0, 0}, 0.5f};
  PointCloud c = synthetic::sample_surface(sphere, 0.01f, 0.0f, 1);
  for (const auto& p : c.positions) c.normals.push_back(p.normalized());
  const KdTreeIndex index(c.positions);
  const float voxel = 0.025f;
  const SparseGrid grid = voxelize(c, VoxelizeConfig{voxel, 0.5f});
  DistanceConfig config;
  const DistanceField field = hoppe_distance(grid, c, index, config);
  for (std::size_t i = 0; i < grid.corners.size(); ++i) {
    const Eigen::Vector3f q = grid.corner_position(i);
    const float truth = q.norm() - sphere.radius;
    if (field.valid[i]) {
      EXPECT_NEAR(field.values[i], truth, 0.05f * voxel) << q.transpose();
    } else {
      EXPECT_GT(std::abs(truth), config.max_distance_voxels * voxel * 0.99f);
    }
  }
}

}  // namespace
}  // namespace meshflow
