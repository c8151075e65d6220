#include "nodes/triangulate/depth_noise.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "nodes/depth/depth_noise.h"
#include "nodes/triangulate/depth_triangulation.h"
#include "runtime/threads.h"

namespace meshflow {
namespace {

// A PrimeSense / Kinect v1 camera: disparity = focal x baseline / depth, in 1/8 pixel steps,
// so a depth step is depth^2 / (8 x focal x baseline) = 0.00317 x depth^2.
constexpr float kNoiseFocal = 525.0f;
constexpr float kBaseline = 0.075f;
constexpr float kQuantisationPerDepth2 = 1.0f / (8.0f * kNoiseFocal * kBaseline);

enum class Noise { kNone, kQuantised, kGaussianPerDepth2 };

// A 640 x 480 F32 frame of the plane through (0, 0, 2) m with normal (0.3, 0.1, -1) in the
// camera frame (a wall seen at an angle, 1.6-2.6 m away), with the given noise: kQuantised as a
// structured-light sensor, Gaussian disparity noise of 1/8 pixel, then rounded to 1/8 pixel.
DepthFrame plane_frame(Noise noise, float sigma_per_depth2 = 0.0f) {
  DepthFrame frame;
  const PinholeIntrinsics& k = frame.intrinsics;
  frame.depth = Image(k.height, k.width, PixelFormat::F32);
  const Eigen::Vector3f normal(0.3f, 0.1f, -1.0f);
  const float offset = normal.dot(Eigen::Vector3f(0, 0, 2));
  std::mt19937 random(7);
  std::normal_distribution<float> gaussian;
  for (int v = 0; v < k.height; ++v)
    for (int u = 0; u < k.width; ++u) {
      const Eigen::Vector3f ray((static_cast<float>(u) - k.cx) / k.fx,
                                (static_cast<float>(v) - k.cy) / k.fy, 1.0f);
      float z = offset / normal.dot(ray);
      if (noise == Noise::kQuantised) {
        const float measured = kNoiseFocal * kBaseline / z + gaussian(random) / 8.0f;
        const float disparity = std::round(8.0f * measured) / 8.0f;
        z = kNoiseFocal * kBaseline / disparity;
      } else if (noise == Noise::kGaussianPerDepth2) {
        const float range = z * ray.norm();
        z *= (range + sigma_per_depth2 * range * range * gaussian(random)) / range;
      }
      frame.depth.at<float>(v, u) = z;
    }
  return frame;
}

TEST(DepthNoise, NoiselessPlaneHasNone) {
  const float noise = estimate_noise_per_depth2(grid_from_depth(plane_frame(Noise::kNone), {}));
  std::printf("[ noise ] noiseless plane: %.2e /m\n", noise);
  EXPECT_LT(noise, 0.02f * kQuantisationPerDepth2);
}

TEST(DepthNoise, GaussianNoiseIsItsNinetiethPercentile) {
  // The residual against the neighbours' midpoint has sigma x sqrt(1.5); its absolute value's
  // 90th percentile is 1.645 of that.
  const float sigma = 0.001f;
  const float noise =
      estimate_noise_per_depth2(grid_from_depth(plane_frame(Noise::kGaussianPerDepth2, sigma), {}));
  const float expected = 1.645f * std::sqrt(1.5f) * sigma;
  std::printf("[ noise ] Gaussian 0.001 x depth^2: %.3e /m (expected %.3e)\n", noise, expected);
  EXPECT_NEAR(noise, expected, 0.05f * expected);
}

// Disparity noise of 1/8 pixel is depth noise of one quantisation step x depth^2 (sigma), and
// the estimate finds it through the rounding.
TEST(DepthNoise, StructuredLightNoiseIsFoundThroughQuantisation) {
  const float noise =
      estimate_noise_per_depth2(grid_from_depth(plane_frame(Noise::kQuantised), {}));
  const float expected = 1.645f * std::sqrt(1.5f) * kQuantisationPerDepth2;
  std::printf("[ noise ] quantised disparity: %.3e /m (expected %.3e)\n", noise, expected);
  EXPECT_NEAR(noise, expected, 0.15f * expected);
}

TEST(DepthNoise, SameEstimateWithOneAndTwoThreads) {
  const PointGrid grid = grid_from_depth(plane_frame(Noise::kGaussianPerDepth2, 0.002f), {});
  float one = 0.0f, two = 0.0f;
  {
    ThreadLimit limit(1);
    one = estimate_noise_per_depth2(grid);
  }
  {
    ThreadLimit limit(2);
    two = estimate_noise_per_depth2(grid);
  }
  EXPECT_GT(one, 0.0f);
  EXPECT_EQ(one, two);
}

// Fusion estimates the noise from the metric depth image itself (depth residuals per depth^2,
// nodes/depth/depth_noise.h): the same figure as the point grid's within the rays' obliquity
// (range residual / range^2 = depth residual / depth^2 / |ray|, |ray| <= 1.25 here).
TEST(DepthNoise, DepthImageEstimateAgreesWithThePointGrids) {
  for (const Noise noise : {Noise::kQuantised, Noise::kGaussianPerDepth2}) {
    const DepthFrame frame = plane_frame(noise, 0.002f);
    const float from_grid = estimate_noise_per_depth2(grid_from_depth(frame, {}));
    float one = 0.0f, two = 0.0f;
    {
      ThreadLimit limit(1);
      one = estimate_noise_per_depth2(frame.depth);
    }
    {
      ThreadLimit limit(2);
      two = estimate_noise_per_depth2(frame.depth);
    }
    std::printf("[ noise ] depth image %.3e /m, point grid %.3e /m\n", one, from_grid);
    EXPECT_EQ(one, two);
    EXPECT_GE(one, 0.95f * from_grid);
    EXPECT_LE(one, 1.3f * from_grid);
  }
  Image empty(480, 640, PixelFormat::F32);
  empty.fill(0.0f);
  EXPECT_EQ(estimate_noise_per_depth2(empty), 0.0f);
}

TEST(DepthNoise, TooFewPixelsGiveNoEstimate) {
  DepthFrame frame = plane_frame(Noise::kGaussianPerDepth2, 0.002f);
  frame.depth.fill(0.0f);
  // One row of 640 pixels: 160 samples (every 2nd, row 100).
  for (int u = 0; u < frame.depth.cols(); ++u) frame.depth.at<float>(100, u) = 2.0f;
  EXPECT_EQ(estimate_noise_per_depth2(grid_from_depth(frame, {})), 0.0f);
}

// The fixed threshold (0.002 x depth^2) is below a Kinect's depth noise, so on a wall the
// quadtree refines to the noise pattern; raised above the frame's own noise it keeps the wall
// coarse, and the triangles' centres stay within that threshold of the true plane.
TEST(DepthNoise, NoiseAwareThresholdKeepsAQuantisedWallCoarse) {
  const DepthFrame frame = plane_frame(Noise::kQuantised);
  DepthTriangulationConfig config;
  config.method = DepthTriangulationMethod::kRestrictedQuadtree;
  config.quadtree.noise_multiple = 0.0f;
  TriangulationCounts fixed_counts, aware_counts;
  const TriangleMesh fixed = triangulate_depth(frame, config, &fixed_counts);
  config.quadtree.noise_multiple = QuadtreeConfig{}.noise_multiple;
  const TriangleMesh aware = triangulate_depth(frame, config, &aware_counts);
  const Eigen::Vector3f normal = Eigen::Vector3f(0.3f, 0.1f, -1.0f).normalized();
  const float offset = normal.dot(Eigen::Vector3f(0, 0, 2));
  float worst = 0.0f;  // distance of a triangle's centre to the plane per squared depth
  for (const Triangle& t : aware.triangles) {
    const Eigen::Vector3f c =
        (aware.vertices[t[0]] + aware.vertices[t[1]] + aware.vertices[t[2]]) / 3.0f;
    worst = std::max(worst, std::abs(normal.dot(c) - offset) / c.squaredNorm());
  }
  std::printf(
      "[ noise ] noisy wall: fixed threshold %.4f -> %zu triangles, noise-aware %.4f -> %zu "
      "triangles; centres within %.4f x depth^2 of the plane\n",
      fixed_counts.threshold_per_depth2, fixed.triangles.size(), aware_counts.threshold_per_depth2,
      aware.triangles.size(), worst);
  EXPECT_EQ(fixed_counts.threshold_per_depth2, QuadtreeConfig{}.error_per_depth2);
  EXPECT_GT(aware_counts.threshold_per_depth2, 2.0f * kQuantisationPerDepth2);
  EXPECT_LT(aware.triangles.size() * 20, fixed.triangles.size());
  EXPECT_LT(worst, aware_counts.threshold_per_depth2);
}

}  // namespace
}  // namespace meshflow
