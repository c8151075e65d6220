#include "nodes/depth/depth_filter.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace meshflow {
namespace {

// A wall at 3 m with a box face at 1.5 m in the middle of the image (an occlusion boundary).
DepthFrame wall_and_box(int w = 80, int h = 60) {
  DepthFrame f;
  f.intrinsics = PinholeIntrinsics{w, h, 60.0f, 60.0f, w / 2.0f - 0.5f, h / 2.0f - 0.5f};
  f.depth = cv::Mat(h, w, CV_16U, cv::Scalar(3000));
  f.depth(cv::Rect(w / 4, h / 4, w / 2, h / 2)).setTo(1500);
  f.depth.at<std::uint16_t>(0, 0) = 0;          // no measurement
  f.depth.at<std::uint16_t>(h - 1, 0) = 60000;  // 60 m: out of range
  return f;
}

TEST(DepthFilter, RemovesInvalidOutOfRangeAndOcclusionEdges) {
  const DepthFrame f = wall_and_box();
  DepthFilterCounts counts;
  const cv::Mat d = filter_depth(f, DepthFilterConfig{}, &counts);
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
  EXPECT_EQ(counts.valid, static_cast<std::size_t>(cv::countNonZero(d > 0.0f)));
}

TEST(DepthFilter, HysteresisKeepsEdgesContinuous) {
  // A ramp whose jumps are weak everywhere but strong at one pixel: the weak run connected to
  // it becomes edge; an isolated weak run elsewhere does not.
  cv::Mat d(20, 40, CV_32F, cv::Scalar(2.0f));
  for (int u = 0; u < 40; ++u) d.at<float>(10, u) = 2.0f * 1.04f;     // 4 % jump: weak
  d.at<float>(10, 20) = 2.0f * 1.2f;                                  // 20 %: strong
  for (int u = 0; u < 5; ++u) d.at<float>(2, u + 30) = 2.0f * 1.04f;  // isolated weak run (row 2)
  const cv::Mat edges = occlusion_edges(d, 0.06f, 0.03f);
  EXPECT_EQ(edges.at<std::uint8_t>(10, 0), 255) << "weak pixel connected to the strong one";
  EXPECT_EQ(edges.at<std::uint8_t>(10, 39), 255);
  EXPECT_EQ(edges.at<std::uint8_t>(2, 32), 0) << "weak run not connected to a strong edge";
  EXPECT_EQ(edges.at<std::uint8_t>(16, 5), 0);
}

// The edge mask by definition: per pixel the largest relative jump to a valid 4-neighbour, then
// weak pixels join the edges until no weak pixel touches one (8-neighbourhood).
cv::Mat occlusion_edges_oracle(const cv::Mat& d, float high, float low) {
  cv::Mat level(d.size(), CV_8U, cv::Scalar(0));
  for (int v = 0; v < d.rows; ++v)
    for (int u = 0; u < d.cols; ++u) {
      const int du[4] = {-1, 1, 0, 0}, dv[4] = {0, 0, -1, 1};
      for (int k = 0; k < 4; ++k) {
        const int x = u + du[k], y = v + dv[k];
        if (x < 0 || y < 0 || x >= d.cols || y >= d.rows) continue;
        const float c = d.at<float>(v, u), n = d.at<float>(y, x);
        if (!(c > 0.0f) || !(n > 0.0f)) continue;
        const float diff = std::abs(c - n), nearer = std::min(c, n);
        const int l = diff > high * nearer ? 2 : diff > low * nearer ? 1 : 0;
        level.at<std::uint8_t>(v, u) = std::max<std::uint8_t>(level.at<std::uint8_t>(v, u), l);
      }
    }
  for (bool grew = true; grew;) {
    grew = false;
    for (int v = 0; v < d.rows; ++v)
      for (int u = 0; u < d.cols; ++u) {
        if (level.at<std::uint8_t>(v, u) != 1) continue;
        for (int y = std::max(v - 1, 0); y <= std::min(v + 1, d.rows - 1); ++y)
          for (int x = std::max(u - 1, 0); x <= std::min(u + 1, d.cols - 1); ++x)
            if (level.at<std::uint8_t>(y, x) == 2 && level.at<std::uint8_t>(v, u) == 1) {
              level.at<std::uint8_t>(v, u) = 2;
              grew = true;
            }
      }
  }
  return level == 2;
}

TEST(DepthFilter, OcclusionEdgesMatchTheDefinitionOnRandomImages) {
  cv::RNG rng(7);
  for (const cv::Size size : {cv::Size(1, 1), cv::Size(2, 3), cv::Size(37, 11), cv::Size(64, 48)})
    for (int trial = 0; trial < 5; ++trial) {
      // Smooth depth with random steps (strong, weak, none) and holes, some NaN and negative.
      cv::Mat d(size, CV_32F);
      for (int v = 0; v < d.rows; ++v)
        for (int u = 0; u < d.cols; ++u) {
          const double r = rng.uniform(0.0, 1.0);
          float& z = d.at<float>(v, u);
          z = static_cast<float>(2.0 * (1.0 + 0.08 * rng.uniform(0.0, 1.0)));
          if (r < 0.08) z = 0.0f;
          if (r > 0.99) z = r > 0.995 ? std::nanf("") : -1.0f;
        }
      const cv::Mat edges = occlusion_edges(d, 0.06f, 0.03f);
      const cv::Mat expected = occlusion_edges_oracle(d, 0.06f, 0.03f);
      ASSERT_EQ(cv::countNonZero(edges != expected), 0)
          << size << " trial " << trial << ": " << cv::countNonZero(expected) << " edge pixels";
      if (size.area() > 100) {
        EXPECT_GT(cv::countNonZero(expected), size.area() / 10);
      }
    }
}

TEST(DepthFilter, MedianDoesNotInventDepthAndEdgesCanBeOff) {
  DepthFrame f = wall_and_box();
  DepthFilterConfig c;
  c.median_kernel = 5;
  c.edge_high = 0.0f;
  DepthFilterCounts counts;
  const cv::Mat d = filter_depth(f, c, &counts);
  EXPECT_EQ(counts.edges, 0u);
  EXPECT_EQ(d.at<float>(0, 0), 0.0f);
  EXPECT_EQ(counts.valid, counts.pixels - 2);
}

}  // namespace
}  // namespace meshflow
