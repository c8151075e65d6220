#pragma once
// The smallest and largest measured depth over square tiles of a depth image, at every
// power-of-two tile size from 2 x 2 up: constant-time, conservative answers to "is every pixel of
// this rectangle measured, and at least this deep?" and "is any pixel of it deeper than this?"
// (TSDF free-space carving asks them per block and per voxel).

#include <cstddef>
#include <vector>

namespace meshflow {

/// Depth bounds over a set of pixels, metres.
struct DepthBounds {
  float min = 0.0f;  ///< the smallest depth; 0 when a pixel is not measured
  float max = 0.0f;  ///< the largest measured depth; 0 when none is
};

class DepthBoundsPyramid {
 public:
  /// Rebuilds the pyramid for a width x height depth image whose pixel (u, v) is
  /// depth[stride * (v * width + u)] (metres; 0 or less, or NaN = not measured). Level l holds
  /// the bounds over tiles of 2^(l + 1) x 2^(l + 1) pixels; buffers are kept across calls.
  /// Parallel over rows; O(pixels).
  void build(const float* depth, std::size_t stride, int width, int height);

  /// Bounds that hold for the pixels [u0, u1] x [v0, v1] (inclusive; inside the image; u0 <= u1,
  /// v0 <= v1): those of the at most 2 x 2 tiles of the smallest level whose tiles are as large
  /// as the rectangle, so they may include pixels up to the rectangle's size (rounded up to a
  /// power of two, at least 2) beyond it: min is at most, max at least the rectangle's own. O(1).
  DepthBounds bounds_over(int u0, int v0, int u1, int v1) const;
  /// The bounds over the whole image (after build(); zeros before). O(1).
  DepthBounds whole_image() const {
    return levels_.empty() || levels_.back().bounds.empty() ? DepthBounds{}
                                                            : levels_.back().bounds[0];
  }

 private:
  struct Level {
    int width = 0, height = 0;
    std::vector<DepthBounds> bounds;  // row-major
  };
  std::vector<Level> levels_;  // levels_[0]: 2 x 2 pixel tiles; each next one halves both sides
};

}  // namespace meshflow
