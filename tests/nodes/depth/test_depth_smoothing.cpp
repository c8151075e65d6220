#include "nodes/depth/depth_smoothing.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "test_support.h"

namespace meshflow {
namespace {

// A wall at 2 m with Gaussian noise (sigma_m), holes (0) at `hole_share` of the pixels.
Image noisy_wall(int rows, int cols, float sigma_m, double hole_share, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, sigma_m);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  Image d(rows, cols, PixelFormat::F32);
  for (int v = 0; v < rows; ++v)
    for (int u = 0; u < cols; ++u)
      d.at<float>(v, u) = uniform(rng) < hole_share ? 0.0f : 2.0f + noise(rng);
  return d;
}

// The median by definition: sort the valid depths of the clipped k x k window, take the element
// at half the count.
Image median_oracle(const Image& d, int k) {
  Image out(d.rows(), d.cols(), PixelFormat::F32);
  for (int v = 0; v < d.rows(); ++v)
    for (int u = 0; u < d.cols(); ++u) {
      if (!(d.at<float>(v, u) > 0.0f)) continue;
      std::vector<float> window;
      for (int y = v - k / 2; y <= v + k / 2; ++y)
        for (int x = u - k / 2; x <= u + k / 2; ++x)
          if (x >= 0 && y >= 0 && x < d.cols() && y < d.rows() && d.at<float>(y, x) > 0.0f)
            window.push_back(d.at<float>(y, x));
      std::sort(window.begin(), window.end());
      out.at<float>(v, u) = window[window.size() / 2];
    }
  return out;
}

double rms_about(const Image& d, float truth) {
  double sum = 0.0;
  std::size_t n = 0;
  for (int v = 2; v < d.rows() - 2; ++v)  // interior: border windows are clipped
    for (int u = 2; u < d.cols() - 2; ++u)
      if (d.at<float>(v, u) > 0.0f) {
        sum += std::pow(d.at<float>(v, u) - truth, 2.0);
        ++n;
      }
  return std::sqrt(sum / static_cast<double>(n));
}

// Bilateral by the definition, in doubles with std::exp.
Image bilateral_oracle(const Image& d, float sigma_depth) {
  Image out(d.rows(), d.cols(), PixelFormat::F32);
  for (int v = 0; v < d.rows(); ++v)
    for (int u = 0; u < d.cols(); ++u) {
      const double centre = d.at<float>(v, u);
      if (!(centre > 0.0)) continue;
      double weighted = 0.0, total = 0.0;
      for (int y = v - 2; y <= v + 2; ++y)
        for (int x = u - 2; x <= u + 2; ++x) {
          if (x < 0 || y < 0 || x >= d.cols() || y >= d.rows()) continue;
          const int r2 = (x - u) * (x - u) + (y - v) * (y - v);
          const double z = d.at<float>(y, x);
          if (r2 > 4 || !(z > 0.0)) continue;
          const double w = std::exp(-r2 / 8.0) * std::exp(-(z - centre) * (z - centre) /
                                                          (2.0 * sigma_depth * sigma_depth));
          weighted += w * z;
          total += w;
        }
      out.at<float>(v, u) = static_cast<float>(weighted / total);
    }
  return out;
}

// Hole shares of 0 and 2 % send most windows through the eight-at-a-time paths, 30 % most
// through the per-pixel ones.
TEST(DepthSmoothing, MedianMatchesTheSortedWindowOnRandomImagesWithHoles) {
  for (const int k : {3, 5})
    for (const double holes : {0.0, 0.02, 0.3})
      for (std::uint32_t seed = 1; seed <= 3; ++seed) {
        const Image d = noisy_wall(23, 31, 0.01f, holes, seed);
        EXPECT_TRUE(median_filter_depth(d, k).same_pixels(median_oracle(d, k)))
            << "k " << k << " holes " << holes << " seed " << seed;
      }
}

TEST(DepthSmoothing, BilateralMatchesTheDefinitionOnRandomImagesWithHoles) {
  for (const double holes : {0.0, 0.02, 0.3})
    for (const float sigma : {0.005f, 0.02f}) {
      const Image d = noisy_wall(23, 31, 0.01f, holes, 5);
      EXPECT_LT(
          test::max_abs_difference(bilateral_filter_depth(d, sigma), bilateral_oracle(d, sigma)),
          2e-6)  // metres: float rounding of a 2 m depth
          << "holes " << holes << " sigma " << sigma;
    }
}

TEST(DepthSmoothing, MedianRemovesASpikeAndIgnoresHoles) {
  Image d = Image::filled<float>(9, 9, 2.0f);
  d.at<float>(4, 4) = 5.0f;                                                  // a flying pixel
  for (int u = 0; u < 9; ++u) d.at<float>(1, u) = d.at<float>(2, u) = 0.0f;  // two rows of holes
  const Image m = median_filter_depth(d, 5);
  EXPECT_EQ(m.at<float>(4, 4), 2.0f);
  // Pixel (3, 4): 15 of its 25 window pixels are holes or the spike's neighbours. A filter that
  // counted holes as depth 0 would give it 0 or a value between; this one keeps the wall.
  EXPECT_EQ(m.at<float>(3, 4), 2.0f);
  EXPECT_EQ(m.at<float>(0, 4), 2.0f);
  for (int u = 0; u < 9; ++u) EXPECT_EQ(m.at<float>(1, u), 0.0f) << "holes stay holes";
}

TEST(DepthSmoothing, BilateralReducesNoiseAndKeepsSteps) {
  Image d = noisy_wall(40, 60, 0.005f, 0.05, 7);
  // A step to 1 m on the right half: an occlusion boundary the filter must not blur.
  for (int v = 0; v < 40; ++v)
    for (int u = 30; u < 60; ++u)
      if (d.at<float>(v, u) > 0.0f) d.at<float>(v, u) -= 1.0f;
  const Image b = bilateral_filter_depth(d, 0.03f);
  Image left(40, 28, PixelFormat::F32), left_in(40, 28, PixelFormat::F32);
  for (int v = 0; v < 40; ++v)
    for (int u = 0; u < 28; ++u) {
      left.at<float>(v, u) = b.at<float>(v, u);
      left_in.at<float>(v, u) = d.at<float>(v, u);
    }
  EXPECT_LT(rms_about(left, 2.0f), 0.5 * rms_about(left_in, 2.0f)) << "noise at least halved";
  for (int v = 0; v < 40; ++v) {
    if (d.at<float>(v, 29) > 0.0f) {
      EXPECT_NEAR(b.at<float>(v, 29), 2.0f, 0.01f) << v;
    }
    if (d.at<float>(v, 30) > 0.0f) {
      EXPECT_NEAR(b.at<float>(v, 30), 1.0f, 0.01f) << v;
    }
    for (int u = 0; u < 60; ++u)
      EXPECT_EQ(b.at<float>(v, u) > 0.0f, d.at<float>(v, u) > 0.0f) << "holes stay holes";
  }
}

TEST(DepthSmoothing, BilateralKeepsAFlatWallFlat) {
  const Image b = bilateral_filter_depth(Image::filled<float>(7, 9, 1.25f), 0.01f);
  EXPECT_LT(test::max_abs_difference(b, Image::filled<float>(7, 9, 1.25f)), 1e-6);
}

TEST(DepthSmoothing, SameResultOnOneAndTwoThreads) {
  const Image d = noisy_wall(120, 160, 0.01f, 0.2, 11);
  for (const bool median : {true, false}) {
    const auto run = [&] {
      return median ? median_filter_depth(d, 5) : bilateral_filter_depth(d, 0.02f);
    };
    const Image one = test::with_threads(1, run), two = test::with_threads(2, run);
    EXPECT_FALSE(one.same_pixels(d)) << "the filter changed nothing";
    EXPECT_TRUE(one.same_pixels(two)) << (median ? "median" : "bilateral");
  }
}

}  // namespace
}  // namespace meshflow
