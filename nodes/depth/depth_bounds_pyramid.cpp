#include "nodes/depth/depth_bounds_pyramid.h"

#include <tbb/parallel_for.h>

#include <algorithm>

namespace meshflow {
namespace {

DepthBounds merged(const DepthBounds& a, const DepthBounds& b) {
  return {std::min(a.min, b.min), std::max(a.max, b.max)};
}

}  // namespace

void DepthBoundsPyramid::build(const float* depth, std::size_t stride, int width, int height) {
  if (levels_.empty()) levels_.emplace_back();
  // The finest level: 2 x 2 pixel tiles, read from the strided image.
  Level& base = levels_[0];
  base.width = (width + 1) / 2;
  base.height = (height + 1) / 2;
  base.bounds.resize(static_cast<std::size_t>(base.width) * static_cast<std::size_t>(base.height));
  const auto pixel = [&](int u, int v) {
    const float d = depth[stride * (static_cast<std::size_t>(v) * static_cast<std::size_t>(width) +
                                    static_cast<std::size_t>(u))];
    const float measured = d > 0.0f ? d : 0.0f;  // NaN too
    return DepthBounds{measured, measured};
  };
  tbb::parallel_for(0, base.height, [&](int v) {
    const int v1 = std::min(2 * v + 1, height - 1);
    DepthBounds* out =
        base.bounds.data() + static_cast<std::size_t>(v) * static_cast<std::size_t>(base.width);
    for (int u = 0; u < base.width; ++u) {
      const int u1 = std::min(2 * u + 1, width - 1);
      out[u] = merged(merged(pixel(2 * u, 2 * v), pixel(u1, 2 * v)),
                      merged(pixel(2 * u, v1), pixel(u1, v1)));
    }
  });
  std::size_t count = 1;
  while (levels_[count - 1].width > 1 || levels_[count - 1].height > 1) {
    if (levels_.size() == count) levels_.emplace_back();
    const Level& fine = levels_[count - 1];
    Level& coarse = levels_[count];
    coarse.width = (fine.width + 1) / 2;
    coarse.height = (fine.height + 1) / 2;
    coarse.bounds.resize(static_cast<std::size_t>(coarse.width) *
                         static_cast<std::size_t>(coarse.height));
    tbb::parallel_for(0, coarse.height, [&](int v) {
      const int v1 = std::min(2 * v + 1, fine.height - 1);
      const auto fine_row = [&](int r) {
        return fine.bounds.data() +
               static_cast<std::size_t>(r) * static_cast<std::size_t>(fine.width);
      };
      const DepthBounds* top = fine_row(2 * v);
      const DepthBounds* bottom = fine_row(v1);
      DepthBounds* out = coarse.bounds.data() +
                         static_cast<std::size_t>(v) * static_cast<std::size_t>(coarse.width);
      for (int u = 0; u < coarse.width; ++u) {
        const int u1 = std::min(2 * u + 1, fine.width - 1);
        out[u] = merged(merged(top[2 * u], top[u1]), merged(bottom[2 * u], bottom[u1]));
      }
    });
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
