// Orientation by propagation: closed solids sampled without normals or a sensor, against their
// exact outward normals.

#include "nodes/normals/orient_normals.h"

#include <gtest/gtest.h>

#include <random>

#include "nodes/normals/normals.h"
#include "nodes/synthetic/closed_objects.h"
#include "runtime/threads.h"
#include "test_support.h"

namespace meshflow {
namespace {

// Share of `normals` within 90 degrees of `truth`.
double share_agreeing(const std::vector<Eigen::Vector3f>& normals,
                      const std::vector<Eigen::Vector3f>& truth) {
  std::size_t agree = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) agree += normals[i].dot(truth[i]) > 0.0f ? 1 : 0;
  return static_cast<double>(agree) / static_cast<double>(truth.size());
}

// Unit normals of `cloud` estimated and oriented by propagation (cloud.normals ignored).
ComputedNormals propagated_normals(PointCloud cloud) {
  cloud.normals.clear();
  const KdTreeIndex index(cloud.positions);
  NormalsConfig config;
  config.orientation = NormalOrientation::kPropagate;
  return compute_normals(cloud, index, config);
}

class ClosedSolid : public ::testing::TestWithParam<int> {
 protected:
  synthetic::ClosedObject object() const {
    return synthetic::closed_test_objects()[static_cast<std::size_t>(GetParam())];
  }
};

TEST_P(ClosedSolid, PropagatedNormalsPointOutward) {
  const synthetic::ClosedObject solid = object();
  const PointCloud samples = solid.sample(30000, 0.0f, 11);
  const ComputedNormals computed = propagated_normals(samples);
  EXPECT_GE(share_agreeing(computed.normals, samples.normals), 0.999) << solid.name;
  EXPECT_EQ(computed.report.orientation, NormalOrientation::kPropagate);
  EXPECT_EQ(computed.report.components, 1u) << solid.name;
  EXPECT_EQ(computed.report.estimated, samples.size());
}

TEST_P(ClosedSolid, NoisySamplesStillPointOutward) {
  // Noise of 0.2 of a voxel of 1 % of the diagonal, as in the reconstruction tests.
  const synthetic::ClosedObject solid = object();
  const PointCloud samples = solid.sample(100000, 0.002f * solid.diagonal(), 12);
  // Plane fits on noisy points can be off by more than 90 degrees whatever the orientation;
  // the bound is on orientation mistakes, which would flip whole regions.
  EXPECT_GE(share_agreeing(propagated_normals(samples).normals, samples.normals), 0.99)
      << solid.name;
}

INSTANTIATE_TEST_SUITE_P(Objects, ClosedSolid, ::testing::Range(0, 6),
                         [](const ::testing::TestParamInfo<int>& param) {
                           return test::closed_object_test_name(param.param);
                         });

TEST(OrientNormals, SameSignsWithOneAndTwoThreads) {
  PointCloud cloud = synthetic::box_with_hole_object().sample(20000, 0.001f, 3);
  std::vector<Eigen::Vector3f> one, two;
  {
    ThreadLimit limit(1);
    one = propagated_normals(cloud).normals;
  }
  {
    ThreadLimit limit(2);
    two = propagated_normals(cloud).normals;
  }
  EXPECT_EQ(one, two);
}

TEST(OrientNormals, TwoSeparateObjectsAreEachTurnedOutward) {
  PointCloud a = synthetic::sphere_object().sample(8000, 0.0f, 4);
  PointCloud b = synthetic::torus_object().sample(8000, 0.0f, 5);
  for (Eigen::Vector3f& p : b.positions) p.x() += 3.0f;
  a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
  a.normals.insert(a.normals.end(), b.normals.begin(), b.normals.end());
  const ComputedNormals computed = propagated_normals(a);
  EXPECT_EQ(computed.report.components, 2u);
  EXPECT_GE(share_agreeing(computed.normals, a.normals), 0.999);
}

TEST(OrientNormals, TheWallOfACavityFacesIntoIt) {
  // A hollow ball: the outer sphere (radius 0.5) faces out, the cavity's wall (radius 0.45, a
  // separate component) faces into the cavity, towards its own centroid.
  synthetic::ClosedObject hollow = synthetic::sphere_object();
  synthetic::SurfacePatch cavity = hollow.patches[0];
  const Eigen::Vector3f centre = hollow.bounds.center();
  cavity.area *= 0.45 * 0.45 / 0.25;
  cavity.draw = [outer = hollow.patches[0].draw, centre](std::mt19937_64& rng, Eigen::Vector3f& p,
                                                         Eigen::Vector3f& n) {
    outer(rng, p, n);
    p = centre + 0.9f * (p - centre);
    n = -n;
  };
  hollow.patches.push_back(cavity);
  const PointCloud samples = hollow.sample(40000, 0.0f, 9);
  const ComputedNormals computed = propagated_normals(samples);
  EXPECT_EQ(computed.report.components, 2u);
  EXPECT_GE(share_agreeing(computed.normals, samples.normals), 0.999);
}

TEST(OrientNormals, FixedPointsKeepTheirSignAndTheRestFollow) {
  // Every normal of the sphere turned inward: with a quarter of them fixed, the others follow
  // the fixed ones, not the outward rule.
  const PointCloud samples = synthetic::sphere_object().sample(10000, 0.0f, 6);
  const KdTreeIndex index(samples.positions);
  const NeighbourTable table = build_neighbour_table(samples.positions, index, 10);
  std::vector<Eigen::Vector3f> scrambled(samples.size());
  std::vector<std::uint8_t> fixed(samples.size(), 0);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    fixed[i] = i % 4 == 0 ? 1 : 0;
    scrambled[i] =
        (fixed[i] || i % 3 == 0) ? Eigen::Vector3f(-samples.normals[i]) : samples.normals[i];
  }
  const OrientedNormals out =
      orient_by_propagation(samples.positions, scrambled, table, fixed, PropagationConfig{});
  for (std::size_t i = 0; i < samples.size(); ++i)
    ASSERT_LT(out.normals[i].dot(samples.normals[i]), 0.0f) << "point " << i;
}

TEST(OrientNormals, AnOpenSheetIsConsistent) {
  // A wavy open sheet: no inside, but one orientation throughout.
  PointCloud sheet;
  for (int i = 0; i < 120; ++i)
    for (int j = 0; j < 120; ++j) {
      const float x = 0.01f * static_cast<float>(i), y = 0.01f * static_cast<float>(j);
      sheet.positions.emplace_back(x, y, 0.1f * std::sin(6.0f * x) * std::cos(4.0f * y));
    }
  const ComputedNormals computed = propagated_normals(sheet);
  std::size_t up = 0;
  for (const Eigen::Vector3f& n : computed.normals) up += n.z() > 0.0f ? 1 : 0;
  EXPECT_TRUE(up == 0 || up == sheet.size()) << up << " of " << sheet.size() << " face up";
}

TEST(OrientNormals, EmptyAndTinyInputs) {
  const NeighbourTable empty_table;
  EXPECT_TRUE(orient_by_propagation({}, {}, empty_table, {}, PropagationConfig{}).normals.empty());
  PointCloud three;
  three.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const ComputedNormals computed = propagated_normals(three);
  ASSERT_EQ(computed.normals.size(), 3u);
  for (const Eigen::Vector3f& n : computed.normals) EXPECT_NEAR(std::abs(n.z()), 1.0f, 1e-5f);
}

}  // namespace
}  // namespace meshflow
