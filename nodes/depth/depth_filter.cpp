#include "nodes/depth/depth_filter.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "nodes/depth/depth_smoothing.h"
#include "runtime/simd.h"

namespace meshflow {
namespace {

// 2 when valid neighbour n differs from valid pixel c by more than `high` of the nearer depth,
// 1 when by more than `low`, else 0. In floats, without divisions or branches, so a whole row
// vectorises. min(c, n) > 0 exactly when both are valid (a negative or NaN depth makes it
// <= 0 or the comparisons false).
inline float jump(float c, float n, float high, float low) {
  const float diff = std::abs(c - n), nearer = std::min(c, n);
  const float level = (diff > high * nearer ? 1.0f : 0.0f) + (diff > low * nearer ? 1.0f : 0.0f);
  return nearer > 0.0f ? level : 0.0f;
}

// The levels of row `row` (the largest jump to any 4-neighbour; `above` / `below` are null at
// the image's top / bottom) into `out`. A missing neighbour is replaced by the pixel itself,
// whose jump is 0. `pairs` (cols + 1 floats) holds the jumps between horizontal neighbours,
// each computed once.
MESHFLOW_AVX2_CLONES void jump_levels(const float* above, const float* row, const float* below,
                                      int cols, float high, float low, float* pairs,
                                      std::uint8_t* out) {
  if (above == nullptr) above = row;
  if (below == nullptr) below = row;
  pairs[0] = pairs[cols] = 0.0f;  // pairs[u] is the jump between u - 1 and u
  for (int u = 1; u < cols; ++u) pairs[u] = jump(row[u - 1], row[u], high, low);
  for (int u = 0; u < cols; ++u) {
    const float c = row[u];
    out[u] = static_cast<std::uint8_t>(
        std::max(std::max(pairs[u], pairs[u + 1]),
                 std::max(jump(c, above[u], high, low), jump(c, below[u], high, low))));
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

MESHFLOW_AVX2_CLONES std::size_t count_changed(const float* before, const float* after, int cols) {
  std::size_t n = 0;
  for (int u = 0; u < cols; ++u) n += before[u] != after[u];
  return n;
}

MESHFLOW_AVX2_CLONES std::size_t count_positive(const float* row, int cols) {
  std::size_t n = 0;
  for (int u = 0; u < cols; ++u) n += row[u] > 0.0f;
  return n;
}

// Appends the linear indices (`first` + column) of the strong (2) pixels of a level row.
// Eight levels at a time: most rows hold few edges.
void append_strong(const std::uint8_t* levels, int cols, int first, std::vector<int>& out) {
  int u = 0;
  for (; u + 8 <= cols; u += 8) {
    std::uint64_t word;
    std::memcpy(&word, levels + u, sizeof word);
    if ((word & 0x0202020202020202ull) == 0) continue;  // levels are 0, 1 or 2
    for (int k = u; k < u + 8; ++k)
      if (levels[k] == 2) out.push_back(first + k);
  }
  for (; u < cols; ++u)
    if (levels[u] == 2) out.push_back(first + u);
}

// Strong levels (2) become 255, the others 0.
MESHFLOW_AVX2_CLONES void strong_to_mask(std::uint8_t* levels, int cols) {
  for (int u = 0; u < cols; ++u) levels[u] = levels[u] == 2 ? 255 : 0;
}

// Zeroes the depths of `row` under a non-zero `mask`; returns how many it zeroed.
MESHFLOW_AVX2_CLONES std::size_t clear_edges(float* row, const std::uint8_t* mask, int cols) {
  std::size_t n = 0;
  for (int u = 0; u < cols; ++u) {
    const bool edge = mask[u] != 0;
    n += edge;
    row[u] = edge ? 0.0f : row[u];
  }
  return n;
}

}  // namespace

Image occlusion_edges(const Image& depth_m, float high, float low) {
  assert(depth_m.format() == PixelFormat::F32 && "depth_m must be F32 metres");
  const int rows = depth_m.rows(), cols = depth_m.cols();
  // 2 = strong edge, 1 = weak candidate, 0 = not an edge.
  Image level(rows, cols, PixelFormat::U8);
  tbb::parallel_for(0, rows, [&](int v) {
    thread_local std::vector<float> pairs;
    pairs.resize(static_cast<std::size_t>(cols) + 1);
    const float* above = v > 0 ? depth_m.ptr<float>(v - 1) : nullptr;
    const float* below = v + 1 < rows ? depth_m.ptr<float>(v + 1) : nullptr;
    jump_levels(above, depth_m.ptr<float>(v), below, cols, high, low, pairs.data(),
                level.ptr<std::uint8_t>(v));
  });
  // Hysteresis: strong pixels (2) seed a breadth-first growth into 8-connected weak ones (1),
  // which become strong; serial, over the strong pixels only.
  std::vector<int> queue;
  for (int v = 0; v < rows; ++v) append_strong(level.ptr<std::uint8_t>(v), cols, v * cols, queue);
  std::uint8_t* levels = level.data();  // rows are contiguous
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const int x = queue[head] % cols, y = queue[head] / cols;
    for (int ny = std::max(y - 1, 0); ny <= std::min(y + 1, rows - 1); ++ny)
      for (int nx = std::max(x - 1, 0); nx <= std::min(x + 1, cols - 1); ++nx) {
        const int n = ny * cols + nx;
        if (levels[n] != 1) continue;
        levels[n] = 2;
        queue.push_back(n);
      }
  }
  for (int v = 0; v < rows; ++v) strong_to_mask(level.ptr<std::uint8_t>(v), cols);
  return level;
}

Image filter_depth(const DepthFrame& frame, const DepthFilterConfig& config,
                   DepthFilterCounts* counts) {
  DepthFilterCounts c;
  Image d = depth_in_metres(frame);
  const int rows = d.rows(), cols = d.cols();
  c.pixels = d.pixels();
  for (int v = 0; v < rows; ++v)
    clear_out_of_range(d.ptr<float>(v), cols, config.min_depth, config.max_depth, c.invalid,
                       c.out_of_range);
  const bool median = config.median_kernel == 3 || config.median_kernel == 5;
  const bool bilateral = config.bilateral_sigma_depth > 0.0f;
  if (median || bilateral) {
    const Image raw = d;  // shares the pixels: the filters return new images
    if (median) d = median_filter_depth(d, config.median_kernel);
    if (bilateral) d = bilateral_filter_depth(d, config.bilateral_sigma_depth);
    for (int v = 0; v < rows; ++v)
      c.smoothed += count_changed(raw.ptr<float>(v), d.ptr<float>(v), cols);
  }
  if (config.edge_high > 0.0f) {
    const Image edges =
        occlusion_edges(d, config.edge_high, std::min(config.edge_low, config.edge_high));
    for (int v = 0; v < rows; ++v)
      c.edges += clear_edges(d.ptr<float>(v), edges.ptr<std::uint8_t>(v), cols);
  }
  for (int v = 0; v < rows; ++v) c.valid += count_positive(d.ptr<float>(v), cols);
  if (counts != nullptr) *counts = c;
  return d;
}

}  // namespace meshflow
