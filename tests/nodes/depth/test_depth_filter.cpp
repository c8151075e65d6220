#include "nodes/depth/depth_filter.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>

namespace meshflow {
namespace {

// A wall at 3 m with a box face at 1.5 m in the middle of the image (an occlusion boundary).
DepthFrame wall_and_box(int w = 80, int h = 60) {
  DepthFrame f;
  f.intrinsics = PinholeIntrinsics{w, h, 60.0f, 60.0f, w / 2.0f - 0.5f, h / 2.0f - 0.5f};
  f.depth = Image::filled<std::uint16_t>(h, w, 3000);
  for (int v = h / 4; v < h / 4 + h / 2; ++v)
    for (int u = w / 4; u < w / 4 + w / 2; ++u) f.depth.at<std::uint16_t>(v, u) = 1500;
  f.depth.at<std::uint16_t>(0, 0) = 0;          // no measurement
  f.depth.at<std::uint16_t>(h - 1, 0) = 60000;  // 60 m: out of range
  return f;
}

TEST(DepthFilter, RemovesInvalidOutOfRangeAndOcclusionEdges) {
  const DepthFrame f = wall_and_box();
  DepthFilterCounts counts;
  const Image d = filter_depth(f, DepthFilterConfig{}, &counts);
  EXPECT_EQ(counts.invalid, 1u);
  EXPECT_EQ(counts.out_of_range, 1u);
  // Both sides of the box outline are edge pixels: the ring inside and the ring outside.
  const int w = 80, h = 60;
  EXPECT_EQ(d.at<float>(h / 4, w / 2), 0.0f) << "box border pixel";
  EXPECT_EQ(d.at<float>(h / 4 - 1, w / 2), 0.0f) << "wall pixel next to the box";
  EXPECT_NEAR(d.at<float>(h / 2, w / 2), 1.5f, 1e-6f) << "box interior stays";
  EXPECT_NEAR(d.at<float>(5, 5), 3.0f, 1e-6f) << "wall interior stays";
  const int outline = 2 * (w / 2 + h / 2) * 2;  // ~ two pixel rings around the box
  EXPECT_NEAR(static_cast<double>(counts.edges), outline, 0.1 * outline);
  EXPECT_EQ(counts.valid, count_nonzero(d));
}

TEST(DepthFilter, HysteresisKeepsEdgesContinuous) {
  // A ramp whose jumps are weak everywhere but strong at one pixel: the weak run connected to
  // it becomes edge; an isolated weak run elsewhere does not.
  Image d = Image::filled<float>(20, 40, 2.0f);
  for (int u = 0; u < 40; ++u) d.at<float>(10, u) = 2.0f * 1.04f;     // 4 % jump: weak
  d.at<float>(10, 20) = 2.0f * 1.2f;                                  // 20 %: strong
  for (int u = 0; u < 5; ++u) d.at<float>(2, u + 30) = 2.0f * 1.04f;  // isolated weak run (row 2)
  const Image edges = occlusion_edges(d, 0.06f, 0.03f);
  EXPECT_EQ(edges.at<std::uint8_t>(10, 0), 255) << "weak pixel connected to the strong one";
  EXPECT_EQ(edges.at<std::uint8_t>(10, 39), 255);
  EXPECT_EQ(edges.at<std::uint8_t>(2, 32), 0) << "weak run not connected to a strong edge";
  EXPECT_EQ(edges.at<std::uint8_t>(16, 5), 0);
}

// The edge mask by definition: per pixel the largest relative jump to a valid 4-neighbour, then
// weak pixels join the edges until no weak pixel touches one (8-neighbourhood).
Image occlusion_edges_oracle(const Image& d, float high, float low) {
  Image level(d.rows(), d.cols(), PixelFormat::U8);
  for (int v = 0; v < d.rows(); ++v)
    for (int u = 0; u < d.cols(); ++u) {
      const int du[4] = {-1, 1, 0, 0}, dv[4] = {0, 0, -1, 1};
      for (int k = 0; k < 4; ++k) {
        const int x = u + du[k], y = v + dv[k];
        if (x < 0 || y < 0 || x >= d.cols() || y >= d.rows()) continue;
        const float c = d.at<float>(v, u), n = d.at<float>(y, x);
        if (!(c > 0.0f) || !(n > 0.0f)) continue;
        const float diff = std::abs(c - n), nearer = std::min(c, n);
        const int l = diff > high * nearer ? 2 : diff > low * nearer ? 1 : 0;
        level.at<std::uint8_t>(v, u) = std::max<std::uint8_t>(level.at<std::uint8_t>(v, u), l);
      }
    }
  for (bool grew = true; grew;) {
    grew = false;
    for (int v = 0; v < d.rows(); ++v)
      for (int u = 0; u < d.cols(); ++u) {
        if (level.at<std::uint8_t>(v, u) != 1) continue;
        for (int y = std::max(v - 1, 0); y <= std::min(v + 1, d.rows() - 1); ++y)
          for (int x = std::max(u - 1, 0); x <= std::min(u + 1, d.cols() - 1); ++x)
            if (level.at<std::uint8_t>(y, x) == 2 && level.at<std::uint8_t>(v, u) == 1) {
              level.at<std::uint8_t>(v, u) = 2;
              grew = true;
            }
      }
  }
  for (int v = 0; v < d.rows(); ++v)
    for (int u = 0; u < d.cols(); ++u)
      level.at<std::uint8_t>(v, u) = level.at<std::uint8_t>(v, u) == 2 ? 255 : 0;
  return level;
}

TEST(DepthFilter, OcclusionEdgesMatchTheDefinitionOnRandomImages) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const std::pair<int, int> sizes[] = {{1, 1}, {3, 2}, {11, 37}, {48, 64}};  // rows, cols
  for (const auto& [rows, cols] : sizes)
    for (int trial = 0; trial < 5; ++trial) {
      // Smooth depth with random steps (strong, weak, none) and holes, some NaN and negative.
      Image d(rows, cols, PixelFormat::F32);
      for (int v = 0; v < d.rows(); ++v)
        for (int u = 0; u < d.cols(); ++u) {
          const double r = uniform(rng);
          float& z = d.at<float>(v, u);
          z = static_cast<float>(2.0 * (1.0 + 0.08 * uniform(rng)));
          if (r < 0.08) z = 0.0f;
          if (r > 0.99) z = r > 0.995 ? std::nanf("") : -1.0f;
        }
      const Image edges = occlusion_edges(d, 0.06f, 0.03f);
      const Image expected = occlusion_edges_oracle(d, 0.06f, 0.03f);
      ASSERT_TRUE(edges.same_pixels(expected)) << rows << "x" << cols << " trial " << trial << ": "
                                               << count_nonzero(expected) << " edge pixels";
      if (rows * cols > 100) {
        EXPECT_GT(count_nonzero(expected), static_cast<std::size_t>(rows * cols / 10));
      }
    }
}

TEST(DepthFilter, MedianDoesNotInventDepthAndEdgesCanBeOff) {
  DepthFrame f = wall_and_box();
  DepthFilterConfig c;
  c.median_kernel = 5;
  c.edge_high = 0.0f;
  DepthFilterCounts counts;
  const Image d = filter_depth(f, c, &counts);
  EXPECT_EQ(counts.edges, 0u);
  EXPECT_EQ(d.at<float>(0, 0), 0.0f);
  EXPECT_EQ(counts.valid, counts.pixels - 2);
  // The median moves the pixels along the box's outline (and next to the holes), drops none.
  EXPECT_GT(counts.smoothed, 0u);
  EXPECT_LT(counts.smoothed, counts.valid / 2);
  DepthFilterCounts plain;
  c.median_kernel = 0;
  filter_depth(f, c, &plain);
  EXPECT_EQ(plain.smoothed, 0u);
  EXPECT_EQ(plain.valid, counts.valid);
}

}  // namespace
}  // namespace meshflow
