#include "nodes/filter/depth_filter.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "runtime/simd.h"

namespace meshflow {
namespace {

// 2 when valid neighbour n differs from valid pixel c by more than `high` of the nearer depth,
// 1 when by more than `low`, else 0 (no divisions, no branches: the row loop vectorises).
inline std::uint8_t jump(float c, float n, float high, float low) {
  const float diff = std::abs(c - n), nearer = std::min(c, n);
  const bool both = (c > 0.0f) & (n > 0.0f);
  return static_cast<std::uint8_t>(both * ((diff > high * nearer) + (diff > low * nearer)));
}

// The levels of row `row` (the largest jump to any 4-neighbour; `above` / `below` are null at
// the image's top / bottom) into `out`.
MESHFLOW_AVX2_CLONES void jump_levels(const float* above, const float* row, const float* below,
                                      int cols, float high, float low, std::uint8_t* out) {
  if (cols == 1) out[0] = 0;
  if (cols >= 2) {  // left and right neighbours (jump() is symmetric)
    out[0] = jump(row[0], row[1], high, low);
    out[cols - 1] = jump(row[cols - 1], row[cols - 2], high, low);
  }
  for (int u = 1; u + 1 < cols; ++u)
    out[u] = std::max(jump(row[u], row[u - 1], high, low), jump(row[u], row[u + 1], high, low));
  for (const float* other : {above, below}) {
    if (other == nullptr) continue;
    for (int u = 0; u < cols; ++u) out[u] = std::max(out[u], jump(row[u], other[u], high, low));
  }
}

// Zeroes the pixels of `row` outside [min_depth, max_depth]; counts the unmeasured (0) and the
// zeroed ones (branch-free, so it vectorises).
MESHFLOW_AVX2_CLONES void clear_out_of_range(float* row, int cols, float min_depth, float max_depth,
                                             std::size_t& invalid, std::size_t& out_of_range) {
  std::size_t unmeasured = 0, outside_count = 0;
  for (int u = 0; u < cols; ++u) {
    const bool measured = row[u] > 0.0f;
    const bool outside = measured & ((row[u] < min_depth) | (row[u] > max_depth));
    unmeasured += !measured;
    outside_count += outside;
    row[u] = outside ? 0.0f : row[u];
  }
  invalid += unmeasured;
  out_of_range += outside_count;
}

MESHFLOW_AVX2_CLONES std::size_t count_positive(const float* row, int cols) {
  std::size_t n = 0;
  for (int u = 0; u < cols; ++u) n += row[u] > 0.0f;
  return n;
}

}  // namespace

cv::Mat occlusion_edges(const cv::Mat& depth_m, float high, float low) {
  CV_Assert(depth_m.type() == CV_32F);
  // 2 = strong edge, 1 = weak candidate, 0 = not an edge.
  cv::Mat level(depth_m.size(), CV_8U, cv::Scalar(0));
  tbb::parallel_for(0, depth_m.rows, [&](int v) {
    const float* above = v > 0 ? depth_m.ptr<float>(v - 1) : nullptr;
    const float* below = v + 1 < depth_m.rows ? depth_m.ptr<float>(v + 1) : nullptr;
    jump_levels(above, depth_m.ptr<float>(v), below, depth_m.cols, high, low,
                level.ptr<std::uint8_t>(v));
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
  for (int v = 0; v < d.rows; ++v)
    clear_out_of_range(d.ptr<float>(v), d.cols, config.min_depth, config.max_depth, c.invalid,
                       c.out_of_range);
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
  for (int v = 0; v < d.rows; ++v) c.valid += count_positive(d.ptr<float>(v), d.cols);
  if (counts != nullptr) *counts = c;
  return d;
}

}  // namespace meshflow
