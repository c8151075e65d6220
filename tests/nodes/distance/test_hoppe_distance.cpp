#include "nodes/distance/hoppe_distance.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "nodes/synthetic/shapes.h"
#include "nodes/voxelize/voxelize.h"
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

TEST(HoppeDistance, NoSurfaceIsContinuedPastTheBorderOfAnOpenPatch) {
  // A 0.4 m square patch at z = 0; voxels of 5 cm. Corners whose foot is more than one voxel
  // past the patch's edge are invalid; above the patch they are valid.
  PointCloud c;
  for (int i = 0; i <= 80; ++i)
    for (int j = 0; j <= 80; ++j) {
      c.positions.emplace_back(0.005f * i, 0.005f * j, 0.0f);
      c.normals.emplace_back(0, 0, 1);
    }
  const KdTreeIndex index(c.positions);
  const float voxel = 0.05f;
  // Grow the grid so that it reaches well past the patch.
  const SparseGrid grid = voxelize(c, VoxelizeConfig{voxel, 2.0f});
  DistanceConfig config;
  config.max_distance_voxels = 10.0f;  // only the extrapolation guard decides here
  config.max_extrapolation_voxels = 1.0f;
  const DistanceField field = hoppe_distance(grid, c, index, config);
  std::size_t beyond = 0, above = 0;
  for (std::size_t i = 0; i < grid.corners.size(); ++i) {
    const Eigen::Vector3f q = grid.corner_position(i);
    const float past = std::max({-q.x(), q.x() - 0.4f, -q.y(), q.y() - 0.4f});
    if (past > 1.2f * voxel) {
      EXPECT_FALSE(field.valid[i]) << q.transpose();
      ++beyond;
    } else if (past < 0.0f) {
      EXPECT_TRUE(field.valid[i]) << q.transpose();
      ++above;
    }
  }
  EXPECT_GT(beyond, 100u);
  EXPECT_GT(above, 100u);
  EXPECT_GT(field.extrapolated, 0u);
  config.max_extrapolation_voxels = 0.0f;  // off: every corner within reach is valid
  EXPECT_EQ(hoppe_distance(grid, c, index, config).valid_count(), grid.corners.size());
}

TEST(HoppeDistance, PlanesThatDisagreeFarFromTheSurfaceInvalidateTheCorner) {
  // Two sheets 0.2 m apart, both with normals +z: the upper one's are turned the wrong way
  // (they should face -z, into the slot). Halfway between, the planes of the lower sheet put a
  // corner a voxel outside and those of the upper one a voxel inside; their average is 0, a
  // phantom surface. With the guard (here at half a voxel) the corner is invalid.
  PointCloud c;
  for (int i = -8; i <= 8; ++i)
    for (int j = -8; j <= 8; ++j)
      for (float z : {0.0f, 0.2f}) {
        c.positions.emplace_back(0.05f * i, 0.05f * j, z);
        c.normals.emplace_back(0, 0, 1);
      }
  const KdTreeIndex index(c.positions);
  const SparseGrid grid = voxelize(c, VoxelizeConfig{0.1f, 1.0f});
  DistanceConfig config;
  config.kd = 10;
  config.max_extrapolation_voxels = 0.0f;
  config.max_disagreement_voxels = 0.5f;
  const DistanceField field = hoppe_distance(grid, c, index, config);
  const std::uint32_t middle = grid.find_corner(Eigen::Vector3i(0, 0, 1));
  ASSERT_NE(middle, UINT32_MAX);
  EXPECT_FALSE(field.valid[middle]);
  EXPECT_GT(field.disagreeing, 0u);
  config.max_disagreement_voxels = 0.0f;
  EXPECT_TRUE(hoppe_distance(grid, c, index, config).valid[middle]);
}

}  // namespace
}  // namespace meshflow
