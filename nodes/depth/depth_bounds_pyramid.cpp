#include "nodes/depth/depth_bounds_pyramid.h"

#include <tbb/parallel_for.h>

#include <algorithm>

namespace meshflow {
namespace {

DepthBounds merged(const DepthBounds& a, const DepthBounds& b) {
  return {std::min(a.min, b.min), std::max(a.max, b.max)};
}

// Fills `coarse` with the bounds over 2 x 2 cells of a width x height grid whose cell (u, v) is
// at(u, v) (cells past the last row or column repeat it). Parallel over rows.
template <class At>
void halve(int width, int height, const At& at, int& coarse_width, int& coarse_height,
           std::vector<DepthBounds>& coarse) {
  coarse_width = (width + 1) / 2;
  coarse_height = (height + 1) / 2;
  coarse.resize(static_cast<std::size_t>(coarse_width) * static_cast<std::size_t>(coarse_height));
  tbb::parallel_for(0, coarse_height, [&](int v) {
    const int v0 = 2 * v, v1 = std::min(v0 + 1, height - 1);
    DepthBounds* out =
        coarse.data() + static_cast<std::size_t>(v) * static_cast<std::size_t>(coarse_width);
    for (int u = 0; u < coarse_width; ++u) {
      const int u0 = 2 * u, u1 = std::min(u0 + 1, width - 1);
      out[u] = merged(merged(at(u0, v0), at(u1, v0)), merged(at(u0, v1), at(u1, v1)));
    }
  });
}

}  // namespace

void DepthBoundsPyramid::build(const float* depth, std::size_t stride, int width, int height) {
  if (levels_.empty()) levels_.emplace_back();
  // The finest level: 2 x 2 pixel tiles, read from the strided image.
  const auto pixel = [&](int u, int v) {
    const float d = depth[stride * (static_cast<std::size_t>(v) * static_cast<std::size_t>(width) +
                                    static_cast<std::size_t>(u))];
    const float measured = d > 0.0f ? d : 0.0f;  // NaN too
    return DepthBounds{measured, measured};
  };
  Level& base = levels_[0];
  halve(width, height, pixel, base.width, base.height, base.bounds);
  std::size_t count = 1;
  while (levels_[count - 1].width > 1 || levels_[count - 1].height > 1) {
    if (levels_.size() == count) levels_.emplace_back();
    const Level& fine = levels_[count - 1];
    const auto cell = [&](int u, int v) {
      return fine.bounds[static_cast<std::size_t>(v) * static_cast<std::size_t>(fine.width) +
                         static_cast<std::size_t>(u)];
    };
    Level& coarse = levels_[count];
    halve(fine.width, fine.height, cell, coarse.width, coarse.height, coarse.bounds);
    ++count;
  }
  levels_.resize(count);
}

DepthBounds DepthBoundsPyramid::bounds_over(int u0, int v0, int u1, int v1) const {
  const int side = std::max(u1 - u0, v1 - v0) + 1;
  std::size_t level = 0;  // tiles of 2^(level + 1) pixels
  while ((2 << level) < side && level + 1 < levels_.size()) ++level;
  const Level& l = levels_[level];
  const int shift = static_cast<int>(level) + 1;
  const int tu0 = u0 >> shift, tu1 = u1 >> shift, tv0 = v0 >> shift, tv1 = v1 >> shift;
  const auto at = [&](int u, int v) {
    return l.bounds[static_cast<std::size_t>(v) * static_cast<std::size_t>(l.width) +
                    static_cast<std::size_t>(u)];
  };
  return merged(merged(at(tu0, tv0), at(tu1, tv0)), merged(at(tu0, tv1), at(tu1, tv1)));
}

}  // namespace meshflow
