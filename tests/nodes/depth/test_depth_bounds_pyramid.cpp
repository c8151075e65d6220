// DepthBoundsPyramid against brute force: its bounds hold for every rectangle (min is 0 whenever
// an unmeasured pixel lies in it), and they look no farther than the rectangle's size beyond it.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "nodes/depth/depth_bounds_pyramid.h"

namespace meshflow {
namespace {

// The bounds over [u0, u1] x [v0, v1] clipped to the image, unmeasured pixels as 0.
DepthBounds brute_bounds(const std::vector<float>& depth, int width, int height, int u0, int v0,
                         int u1, int v1) {
  DepthBounds b{1e30f, 0.0f};
  for (int v = std::max(v0, 0); v <= std::min(v1, height - 1); ++v)
    for (int u = std::max(u0, 0); u <= std::min(u1, width - 1); ++u) {
      const float d = depth[static_cast<std::size_t>(v * width + u)];
      const float measured = d > 0.0f ? d : 0.0f;
      b.min = std::min(b.min, measured);
      b.max = std::max(b.max, measured);
    }
  return b;
}

TEST(DepthBoundsPyramid, BoundsHoldForEveryRectangleAndLookOnlyNearby) {
  std::mt19937 rng(7);
  for (const auto& [width, height] : {std::pair{37, 23}, std::pair{64, 48}, std::pair{1, 9}}) {
    // Depth 1..3 m with some unmeasured pixels (0 and NaN); stored with stride 2.
    std::vector<float> pixels(2 * static_cast<std::size_t>(width * height), -1.0f);
    std::vector<float> depth(static_cast<std::size_t>(width * height));
    std::uniform_real_distribution<float> metres(1.0f, 3.0f);
    for (std::size_t i = 0; i < depth.size(); ++i) {
      const std::uint32_t r = rng() % 100;
      depth[i] = r == 0 ? 0.0f : r == 1 ? std::nanf("") : metres(rng);
      pixels[2 * i] = depth[i];
    }
    DepthBoundsPyramid pyramid;
    pyramid.build(pixels.data(), 2, width, height);
    for (int trial = 0; trial < 2000; ++trial) {
      const int u0 = static_cast<int>(rng() % static_cast<std::uint32_t>(width));
      const int v0 = static_cast<int>(rng() % static_cast<std::uint32_t>(height));
      const int u1 = u0 + static_cast<int>(rng() % static_cast<std::uint32_t>(width - u0));
      const int v1 = v0 + static_cast<int>(rng() % static_cast<std::uint32_t>(height - v0));
      const DepthBounds got = pyramid.bounds_over(u0, v0, u1, v1);
      const DepthBounds inside = brute_bounds(depth, width, height, u0, v0, u1, v1);
      ASSERT_LE(got.min, inside.min) << u0 << " " << v0 << " " << u1 << " " << v1;
      ASSERT_GE(got.max, inside.max) << u0 << " " << v0 << " " << u1 << " " << v1;
      // The tiles reach at most the rectangle's larger side beyond it (rounded up to a power of
      // two, at least 2), so the bounds lie within those of that dilated rectangle.
      int side = 2;
      while (side < std::max(u1 - u0, v1 - v0) + 1) side *= 2;
      const DepthBounds around =
          brute_bounds(depth, width, height, u0 - side, v0 - side, u1 + side, v1 + side);
      ASSERT_GE(got.min, around.min);
      ASSERT_LE(got.max, around.max);
    }
  }
}

TEST(DepthBoundsPyramid, RebuildsForANewImageOfAnotherSize) {
  DepthBoundsPyramid pyramid;
  std::vector<float> big(2 * 40 * 30, 2.0f);
  pyramid.build(big.data(), 2, 40, 30);
  EXPECT_EQ(pyramid.bounds_over(0, 0, 39, 29).min, 2.0f);
  std::vector<float> small = {5.0f, 4.0f, 3.0f};  // stride 1, 3 x 1
  pyramid.build(small.data(), 1, 3, 1);
  EXPECT_EQ(pyramid.bounds_over(0, 0, 1, 0).min, 4.0f);
  EXPECT_EQ(pyramid.bounds_over(0, 0, 1, 0).max, 5.0f);
  EXPECT_EQ(pyramid.bounds_over(0, 0, 2, 0).min, 3.0f);
  EXPECT_EQ(pyramid.bounds_over(2, 0, 2, 0).max, 3.0f);  // its 2 x 2 tile holds only itself
  EXPECT_EQ(pyramid.whole_image().min, 3.0f);
  EXPECT_EQ(pyramid.whole_image().max, 5.0f);
  EXPECT_EQ(DepthBoundsPyramid().whole_image().max, 0.0f);
}

}  // namespace
}  // namespace meshflow
