#pragma once
// Depth-image filtering: range limits, optional median / bilateral smoothing, and removal of
// occlusion edges (depth discontinuities) with hysteresis, as in the depth-map triangulation
// work the method builds on. Output is depth in metres (F32, 0 = invalid).

#include <cstddef>

#include "runtime/depth_frame.h"
#include "runtime/image.h"

namespace meshflow {

struct DepthFilterConfig {
  float min_depth = 0.1f;              ///< metres; nearer pixels are invalid
  float max_depth = 10.0f;             ///< metres; farther pixels are invalid
  int median_kernel = 0;               ///< 3 or 5 = median_filter_depth() of that size; 0 = off
  float bilateral_sigma_depth = 0.0f;  ///< metres; > 0 enables bilateral_filter_depth()
  /// Relative depth jump |d - d_n| / min(d, d_n) to a 4-neighbour that marks an occlusion edge:
  /// pixels above `edge_high` are edges, pixels above `edge_low` are edges when connected
  /// (8-neighbourhood) to one, so edges are continuous. 0 disables edge removal.
  float edge_high = 0.06f;
  float edge_low = 0.03f;
};

struct DepthFilterCounts {
  std::size_t pixels = 0;
  std::size_t invalid = 0;  ///< no measurement in the input
  std::size_t out_of_range = 0;
  std::size_t edges = 0;  ///< removed as occlusion edges
  std::size_t valid = 0;  ///< left for back-projection
  /// Pixels whose depth the median / bilateral smoothing moved (the smoothing drops none: a
  /// pixel is valid after it exactly when it was before).
  std::size_t smoothed = 0;
};

/// Filters `frame`'s depth. Deterministic; O(pixels).
Image filter_depth(const DepthFrame& frame, const DepthFilterConfig& config,
                   DepthFilterCounts* counts = nullptr);

/// Occlusion-edge mask (U8, 255 = edge) of a metric depth image (0 = invalid), with
/// hysteresis between `low` and `high` relative jumps. `depth_m` must be F32 (asserted).
/// O(pixels).
Image occlusion_edges(const Image& depth_m, float high, float low);

}  // namespace meshflow
