#include "nodes/filter/spatial_order.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "nodes/synthetic/closed_objects.h"
#include "runtime/threads.h"

namespace meshflow {
namespace {

TEST(SpatialOrder, IsAPermutationThatKeepsNeighboursClose) {
  PointCloud cloud = synthetic::sphere_object().sample(20000, 0.0f, 1);
  cloud.colors.assign(cloud.size(), Rgb8{1, 2, 3});
  const std::vector<std::uint32_t> order = morton_order(cloud);
  std::vector<std::uint32_t> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], i);
  // Consecutive points lie far closer together than in the random order they were drawn in.
  auto mean_step = [](const PointCloud& c) {
    double sum = 0.0;
    for (std::size_t i = 1; i < c.size(); ++i) sum += (c.positions[i] - c.positions[i - 1]).norm();
    return sum / static_cast<double>(c.size() - 1);
  };
  const PointCloud ordered = in_morton_order(cloud);
  EXPECT_LT(mean_step(ordered), 0.1 * mean_step(cloud));
  ASSERT_EQ(ordered.normals.size(), cloud.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    ASSERT_EQ(ordered.positions[i], cloud.positions[order[i]]);
    ASSERT_EQ(ordered.normals[i], cloud.normals[order[i]]);
  }
  EXPECT_EQ(ordered.colors.size(), cloud.size());
}

TEST(SpatialOrder, SameOrderWithOneAndTwoThreadsAndOrganizedCloudsUntouched) {
  const PointCloud cloud = synthetic::torus_object().sample(70000, 0.001f, 2);
  std::vector<std::uint32_t> one, two;
  {
    ThreadLimit limit(1);
    one = morton_order(cloud);
  }
  {
    ThreadLimit limit(2);
    two = morton_order(cloud);
  }
  EXPECT_EQ(one.size(), cloud.size());
  EXPECT_EQ(one, two);
  PointCloud grid;
  grid.width = 2;
  grid.height = 2;
  grid.positions = {{1, 1, 1}, {0, 0, 0}, {NAN, NAN, NAN}, {0.5f, 0, 0}};
  const PointCloud kept = in_morton_order(grid);
  EXPECT_TRUE(kept.is_organized());
  EXPECT_EQ(kept.positions[0], grid.positions[0]);
}

TEST(SpatialOrder, DegenerateInputs) {
  EXPECT_TRUE(morton_order(PointCloud{}).empty());
  PointCloud same;
  same.positions.assign(5, Eigen::Vector3f(1, 2, 3));
  same.positions.emplace_back(NAN, 0, 0);
  const std::vector<std::uint32_t> order = morton_order(same);
  EXPECT_EQ(order.size(), 6u);
}

}  // namespace
}  // namespace meshflow
