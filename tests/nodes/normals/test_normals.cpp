#include "nodes/normals/normals.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "nodes/synthetic/closed_objects.h"
#include "nodes/synthetic/shapes.h"
#include "runtime/error.h"
#include "runtime/threads.h"

namespace meshflow {
namespace {

TEST(Normals, PlaneNormalsFaceTheViewpoint) {
  PointCloud c;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j) c.positions.emplace_back(0.01f * i, 0.01f * j, 0.0f);
  c.sensor_origin = Eigen::Vector3f(0.2f, 0.2f, -1.0f);
  c.has_sensor_origin = true;
  const KdTreeIndex index(c.positions);
  const auto normals = estimate_normals(c, index, NormalsConfig{});
  for (const auto& n : normals) EXPECT_NEAR(n.z(), -1.0f, 1e-4f);
}

TEST(Normals, SphereNormalsMatchTheAnalyticOnesAndPointOutward) {
  const synthetic::Sphere sphere{{0.1f, -0.2f, 0.3f}, 1.0f};
  PointCloud c = synthetic::sample_surface(sphere, 0.03f, 0.0f, 1);
  NormalsConfig config;
  config.orientation = NormalOrientation::kAwayFromViewpoint;
  config.viewpoint = sphere.center;
  const KdTreeIndex index(c.positions);
  const auto normals = estimate_normals(c, index, config);
  double worst = 0.0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    const Eigen::Vector3f truth = (c.positions[i] - sphere.center).normalized();
    worst = std::max(worst, std::acos(std::min(1.0f, normals[i].dot(truth))) * 180.0 / M_PI);
  }
  EXPECT_LT(worst, 3.0) << "degrees";
}

TEST(Normals, AdaptiveKFixesLaserLineNeighbourhoods) {
  // Scan lines: dense along x (1 mm), 5 cm apart in y, on the plane z = 0.2 x.
  PointCloud c;
  for (int row = 0; row < 10; ++row)
    for (int i = 0; i < 300; ++i) {
      const float x = 0.001f * i, y = 0.05f * row;
      c.positions.emplace_back(x, y, 0.2f * x);
    }
  c.sensor_origin = Eigen::Vector3f(0.15f, 0.25f, 1.0f);
  c.has_sensor_origin = true;
  const KdTreeIndex index(c.positions);
  const Eigen::Vector3f truth = Eigen::Vector3f(-0.2f, 0.0f, 1.0f).normalized();
  NormalsConfig config;
  config.ki = 0;
  auto bad_fraction = [&](const std::vector<Eigen::Vector3f>& normals) {
    std::size_t bad = 0;
    for (const auto& n : normals) bad += n.dot(truth) < 0.99f ? 1 : 0;
    return static_cast<double>(bad) / static_cast<double>(normals.size());
  };
  const double fixed = bad_fraction(estimate_normals(c, index, config));
  config.adaptive_k = true;
  config.adaptive_max_k = 1200;
  const double adaptive = bad_fraction(estimate_normals(c, index, config));
  EXPECT_GT(fixed, 0.5) << "collinear neighbourhoods make fixed-k PCA ill-posed";
  EXPECT_LT(adaptive, 0.05);
}

TEST(Normals, FitPlaneNormal) {
  const std::vector<Eigen::Vector3f> pts = {{0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}};
  EXPECT_NEAR(std::abs(fit_plane_normal(pts).z()), 1.0f, 1e-6f);
  EXPECT_TRUE(fit_plane_normal({{0, 0, 0}}).isZero());
}

TEST(Normals, SameResultWithOneAndTwoThreads) {
  PointCloud c = synthetic::sample_surface(synthetic::Box{}, 0.05f, 0.005f, 3);
  c.has_sensor_origin = true;
  const KdTreeIndex index(c.positions);
  std::vector<Eigen::Vector3f> one, two;
  {
    ThreadLimit limit(1);
    one = estimate_normals(c, index, NormalsConfig{});
  }
  {
    ThreadLimit limit(2);
    two = estimate_normals(c, index, NormalsConfig{});
  }
  ASSERT_EQ(one.size(), c.size());
  EXPECT_TRUE(std::all_of(one.begin(), one.end(), [](const Eigen::Vector3f& n) {
    return std::abs(n.norm() - 1.0f) < 1e-4f;
  }));
  EXPECT_EQ(one, two);
}

TEST(Normals, InputNormalsAreUsedAndMissingOnesEstimatedFromTheirNeighbours) {
  PointCloud c = synthetic::sample_surface(synthetic::Sphere{}, 0.05f, 0.0f, 4);
  c.normals.resize(c.size());
  std::size_t missing = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    const Eigen::Vector3f truth = c.positions[i].normalized();
    if (i % 7 == 0) {  // missing: NaN, zero
      c.normals[i] = i % 2 ? Eigen::Vector3f::Constant(NAN) : Eigen::Vector3f::Zero();
      ++missing;
    } else {
      c.normals[i] = 3.0f * truth;  // not unit length: normalised
    }
  }
  const KdTreeIndex index(c.positions);
  const ComputedNormals computed = compute_normals(c, index, NormalsConfig{});
  EXPECT_EQ(computed.report.source, NormalSource::kInput);
  EXPECT_EQ(computed.report.estimated, missing);
  for (std::size_t i = 0; i < c.size(); ++i) {
    const Eigen::Vector3f truth = c.positions[i].normalized();
    ASSERT_NEAR(computed.normals[i].norm(), 1.0f, 1e-5f);
    if (i % 7 == 0)
      EXPECT_GT(computed.normals[i].dot(truth), 0.95f) << "estimated point " << i;
    else
      EXPECT_NEAR(computed.normals[i].dot(truth), 1.0f, 1e-5f) << "input point " << i;
  }
}

TEST(Normals, SourceAndOrientationChoices) {
  PointCloud c = synthetic::sample_surface(synthetic::Sphere{}, 0.1f, 0.0f, 5);
  const KdTreeIndex index(c.positions);
  NormalsConfig input_only;
  input_only.source = NormalSource::kInput;
  EXPECT_THROW(compute_normals(c, index, input_only), Error);  // the cloud has none
  EXPECT_EQ(resolve_orientation(c), NormalOrientation::kPropagate);
  c.has_sensor_origin = true;
  EXPECT_EQ(resolve_orientation(c), NormalOrientation::kTowardSensor);
  c.has_sensor_origin = false;
  c.normals.assign(c.size(), Eigen::Vector3f::Constant(NAN));
  EXPECT_THROW(compute_normals(c, index, input_only), Error);  // none usable
  // Estimation with the input's signs: every input normal NaN, so propagation decides.
  NormalsConfig estimate;
  estimate.source = NormalSource::kEstimate;
  const ComputedNormals computed = compute_normals(c, index, estimate);
  EXPECT_EQ(computed.report.orientation, NormalOrientation::kPropagate);
  for (std::size_t i = 0; i < c.size(); ++i)
    EXPECT_GT(computed.normals[i].dot(c.positions[i]), 0.0f);
}

TEST(Normals, SharpFeatureNormalsKeepEachFaceNormalUpToTheEdge) {
  // A box sampled uniformly: plane fits beside an edge blend the two faces; with sharp normals
  // nearly every point gets its own face's normal.
  const synthetic::ClosedObject box = synthetic::box_object();
  PointCloud c = box.sample(40000, 0.0f, 8);
  const std::vector<Eigen::Vector3f> truth = c.normals;
  c.normals.clear();
  const KdTreeIndex index(c.positions);
  auto off_by_more_than_5_degrees = [&](const NormalsConfig& config) {
    const std::vector<Eigen::Vector3f> n = compute_normals(c, index, config).normals;
    std::size_t off = 0;
    for (std::size_t i = 0; i < c.size(); ++i) off += std::abs(n[i].dot(truth[i])) < 0.9962f;
    return off;
  };
  NormalsConfig config;
  const std::size_t blended = off_by_more_than_5_degrees(config);
  config.sharp = NormalsConfig::Sharp::kOn;
  const std::size_t sharp = off_by_more_than_5_degrees(config);
  std::printf("[ normals ] box, more than 5 degrees off: %zu plain, %zu sharp of %zu\n", blended,
              sharp, c.size());
  EXPECT_GT(blended, c.size() / 50);
  EXPECT_LT(sharp, c.size() / 500);
}

TEST(Normals, CollinearPointsGetFiniteUnitNormals) {
  // No plane is defined; any direction perpendicular to the line is a documented fallback.
  PointCloud c;
  for (int i = 0; i < 50; ++i) c.positions.emplace_back(0.01f * i, 0.0f, 0.0f);
  const KdTreeIndex index(c.positions);
  for (NormalOrientation o : {NormalOrientation::kPropagate, NormalOrientation::kTowardSensor}) {
    NormalsConfig config;
    config.orientation = o;
    for (const Eigen::Vector3f& n : compute_normals(c, index, config).normals) {
      ASSERT_TRUE(n.allFinite());
      EXPECT_NEAR(n.norm(), 1.0f, 1e-4f);
      EXPECT_NEAR(n.x(), 0.0f, 1e-3f);
    }
  }
}

}  // namespace
}  // namespace meshflow
