#include "nodes/filter/depth_filter.h"

#include <gtest/gtest.h>

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
