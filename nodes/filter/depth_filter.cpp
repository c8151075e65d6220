#include "nodes/filter/depth_filter.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace meshflow {
namespace {

// 2 when some valid 4-neighbour differs from pixel u of row `row` by more than `high` of the
// nearer depth, 1 when by more than `low`, else 0 (comparisons without divisions).
std::uint8_t jump_level(const float* above, const float* row, const float* below, int u, int cols,
                        float high, float low) {
  const float c = row[u];
  std::uint8_t level = 0;
  auto check = [&](float n) {
    if (!(n > 0.0f)) return;
    const float diff = std::abs(c - n), nearer = std::min(c, n);
    if (diff > high * nearer)
      level = 2;
    else if (diff > low * nearer && level == 0)
      level = 1;
  };
  if (u + 1 < cols) check(row[u + 1]);
  if (u > 0) check(row[u - 1]);
  if (below != nullptr) check(below[u]);
  if (above != nullptr) check(above[u]);
  return level;
}

}  // namespace

cv::Mat occlusion_edges(const cv::Mat& depth_m, float high, float low) {
  CV_Assert(depth_m.type() == CV_32F);
  // 2 = strong edge, 1 = weak candidate, 0 = not an edge.
  cv::Mat level(depth_m.size(), CV_8U, cv::Scalar(0));
  tbb::parallel_for(0, depth_m.rows, [&](int v) {
    const float* row = depth_m.ptr<float>(v);
    const float* above = v > 0 ? depth_m.ptr<float>(v - 1) : nullptr;
    const float* below = v + 1 < depth_m.rows ? depth_m.ptr<float>(v + 1) : nullptr;
    std::uint8_t* out = level.ptr<std::uint8_t>(v);
    for (int u = 0; u < depth_m.cols; ++u) {
      if (!(row[u] > 0.0f)) continue;
      out[u] = jump_level(above, row, below, u, depth_m.cols, high, low);
    }
  });
  // Hysteresis: grow strong edges into connected weak pixels (breadth-first, serial).
  cv::Mat edges(depth_m.size(), CV_8U, cv::Scalar(0));
  std::vector<cv::Point> queue;
  for (int v = 0; v < level.rows; ++v)
    for (int u = 0; u < level.cols; ++u)
      if (level.at<std::uint8_t>(v, u) == 2) {
        edges.at<std::uint8_t>(v, u) = 255;
        queue.emplace_back(u, v);
      }
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const cv::Point p = queue[head];
    for (int dv = -1; dv <= 1; ++dv)
      for (int du = -1; du <= 1; ++du) {
        const int x = p.x + du, y = p.y + dv;
        if (x < 0 || y < 0 || x >= level.cols || y >= level.rows) continue;
        if (level.at<std::uint8_t>(y, x) == 1 && edges.at<std::uint8_t>(y, x) == 0) {
          edges.at<std::uint8_t>(y, x) = 255;
          queue.emplace_back(x, y);
        }
      }
  }
  return edges;
}

cv::Mat filter_depth(const DepthFrame& frame, const DepthFilterConfig& config,
                     DepthFilterCounts* counts) {
  run_opencv_on_calling_thread();
  DepthFilterCounts c;
  cv::Mat d = depth_in_metres(frame);
  c.pixels = static_cast<std::size_t>(d.total());
  for (int v = 0; v < d.rows; ++v) {
    float* row = d.ptr<float>(v);
    for (int u = 0; u < d.cols; ++u) {
      if (row[u] <= 0.0f) {
        ++c.invalid;
      } else if (row[u] < config.min_depth || row[u] > config.max_depth) {
        row[u] = 0.0f;
        ++c.out_of_range;
      }
    }
  }
  if (config.median_kernel == 3 || config.median_kernel == 5) {
    cv::Mat smoothed;
    cv::medianBlur(d, smoothed, config.median_kernel);
    // Smoothing must not invent depth where there was none.
    smoothed.setTo(0.0f, d <= 0.0f);
    d = smoothed;
  }
  if (config.bilateral_sigma_depth > 0.0f) {
    cv::Mat smoothed;
    cv::bilateralFilter(d, smoothed, 5, config.bilateral_sigma_depth, 2.0);
    smoothed.setTo(0.0f, d <= 0.0f);
    d = smoothed;
  }
  if (config.edge_high > 0.0f) {
    const cv::Mat edges =
        occlusion_edges(d, config.edge_high, std::min(config.edge_low, config.edge_high));
    c.edges = static_cast<std::size_t>(cv::countNonZero(edges));
    d.setTo(0.0f, edges);
  }
  c.valid = static_cast<std::size_t>(cv::countNonZero(d > 0.0f));
  if (counts != nullptr) *counts = c;
  return d;
}

}  // namespace meshflow
