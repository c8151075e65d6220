#include "nodes/filter/filter.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

#include "runtime/threads.h"
#include "runtime/voxel_key.h"

namespace meshflow {
namespace {

PointCloud random_cloud(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  PointCloud c;
  for (std::size_t i = 0; i < n; ++i) c.positions.emplace_back(u(rng), u(rng), u(rng));
  return c;
}

TEST(Filter, RemovesAndCountsNonFinitePoints) {
  PointCloud c = random_cloud(100, 1);
  c.positions[3].x() = std::nanf("");
  c.positions[50].z() = INFINITY;
  FilterCounts counts;
  const PointCloud out = filter_cloud(c, FilterConfig{}, &counts);
  EXPECT_EQ(counts.non_finite, 2u);
  EXPECT_EQ(out.size(), 98u);
  EXPECT_EQ(counts.output, 98u);
}

TEST(Filter, CropBoxAndRange) {
  PointCloud c = random_cloud(5000, 2);
  c.sensor_origin = Eigen::Vector3f(0.5f, 0, 0);
  c.has_sensor_origin = true;
  FilterConfig config;
  config.crop_min = Eigen::Vector3f(-1, -1, -0.5f);
  config.crop_max = Eigen::Vector3f(1, 1, 0.5f);
  config.min_range = 0.2f;
  config.max_range = 0.9f;
  const PointCloud out = filter_cloud(c, config);
  std::size_t expected = 0;
  for (const auto& p : c.positions) {
    const float r = (p - c.sensor_origin).norm();
    expected += (std::abs(p.z()) <= 0.5f && r >= 0.2f && r <= 0.9f) ? 1 : 0;
  }
  EXPECT_EQ(out.size(), expected);
  for (const auto& p : out.positions) EXPECT_LE(std::abs(p.z()), 0.5f);
}

TEST(Filter, VoxelGridMatchesBruteForceCentroids) {
  const PointCloud c = random_cloud(20000, 3);
  const float voxel = 0.1f;
  std::map<VoxelKey, std::pair<Eigen::Vector3d, int>> cells;
  for (const auto& p : c.positions) {
    auto& cell = cells[pack_key(cell_of(p, voxel))];
    if (cell.second == 0) cell.first.setZero();
    cell.first += p.cast<double>();
    ++cell.second;
  }
  const PointCloud out = voxel_grid_downsample(c, voxel);
  ASSERT_EQ(out.size(), cells.size());
  std::size_t i = 0;
  for (const auto& [key, sum] : cells) {  // std::map iterates in key order, like the output
    EXPECT_TRUE(out.positions[i].isApprox((sum.first / sum.second).cast<float>(), 1e-5f));
    ++i;
  }
}

TEST(Filter, StatisticalOutlierRemovalDropsIsolatedPoints) {
  PointCloud c = random_cloud(2000, 4);
  c.positions.emplace_back(10, 10, 10);
  c.positions.emplace_back(-10, 5, 0);
  const auto inliers = statistical_inlier_indices(c, 8, 1.0f);
  EXPECT_EQ(std::count(inliers.begin(), inliers.end(), 2000u), 0);
  EXPECT_EQ(std::count(inliers.begin(), inliers.end(), 2001u), 0);
  EXPECT_GT(inliers.size(), 1800u);
}

TEST(Filter, SameResultWithOneAndTwoThreads) {
  const PointCloud c = random_cloud(30000, 5);
  FilterConfig config;
  config.voxel_size = 0.05f;
  config.outlier_k = 8;
  PointCloud one, two;
  {
    ThreadLimit limit(1);
    one = filter_cloud(c, config);
  }
  {
    ThreadLimit limit(2);
    two = filter_cloud(c, config);
  }
  EXPECT_GT(one.positions.size(), 100u);
  EXPECT_LT(one.positions.size(), c.positions.size());  // the voxel grid thinned it
  EXPECT_EQ(one.positions, two.positions);
}

TEST(Filter, PrincipalExtentsTellLinesFromPlanes) {
  PointCloud c;
  for (int i = 0; i < 100; ++i) c.positions.emplace_back(0.1f * i, 0.2f * i, 1.0f);
  c.positions.emplace_back(NAN, 0.0f, 0.0f);  // ignored
  Eigen::Vector3d e = principal_extents(c);
  EXPECT_LT(e[1], 1e-5);
  EXPECT_GT(e[2], 1.0);
  for (int i = 0; i < 100; ++i) c.positions.emplace_back(0.1f * i, 0.0f, 1.0f);
  e = principal_extents(c);
  EXPECT_LT(e[0], 1e-5);
  EXPECT_GT(e[1], 0.1);
  EXPECT_EQ(principal_extents(PointCloud{}), Eigen::Vector3d::Zero());
}

}  // namespace
}  // namespace meshflow
