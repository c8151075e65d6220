#include "nodes/eval/truth_eval.h"

#include <gtest/gtest.h>

#include <cmath>

#include "test_support.h"

namespace meshflow {
namespace {

TEST(TruthEval, AreaSamplesAreUniformAndDistancesExact) {
  // The unit grid (10 x 10 m square at z = 0) against the plane z = 0.25: every distance is 0.25;
  // samples spread evenly over the square's four quadrants.
  const TriangleMesh grid = test::grid_mesh(11);
  const std::vector<Eigen::Vector3f> samples = surface_samples(grid, 40000, 7);
  ASSERT_EQ(samples.size(), 40000u);
  std::size_t quadrant[4] = {0, 0, 0, 0};
  for (const Eigen::Vector3f& p : samples) {
    ASSERT_GE(p.x(), 0.0f);
    ASSERT_LE(p.x(), 10.0f);
    ++quadrant[(p.x() > 5.0f ? 1 : 0) + (p.y() > 5.0f ? 2 : 0)];
  }
  for (std::size_t q : quadrant) EXPECT_NEAR(static_cast<double>(q), 10000.0, 400.0);
  const TruthEvaluation e = evaluate_against_truth(
      grid, [](const Eigen::Vector3f& p) { return std::abs(p.z() - 0.25f); }, 1000);
  EXPECT_NEAR(e.vertices.mean, 0.25, 1e-6);
  EXPECT_NEAR(e.area.p95, 0.25, 1e-6);
  EXPECT_EQ(e.area.samples, 1000u);
  EXPECT_FALSE(e.topology.edges.closed());
  EXPECT_TRUE(surface_samples(TriangleMesh{}, 10).empty());
}

}  // namespace
}  // namespace meshflow
