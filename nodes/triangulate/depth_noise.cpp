#include "nodes/triangulate/depth_noise.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <array>
#include <cstdint>

namespace meshflow {
namespace {

// Residuals per depth^2 are binned linearly up to kRange (1/m); larger ones share the last bin.
constexpr int kBins = 2048;
constexpr float kRange = 0.05f;
using Histogram = std::array<std::uint32_t, kBins + 1>;
// Every 4th row, every 2nd pixel: tens of thousands of samples for a 640 x 480 frame, plenty
// for a percentile, at a tenth of a millisecond.
constexpr int kRowStep = 4;
constexpr int kColumnStep = 2;

void add_row(const PointGrid& g, int v, Histogram& h) {
  const Eigen::Vector3f* row = &g.points[g.index(0, v)];
  for (int u = 1; u + 1 < g.width; u += kColumnStep) {
    const Eigen::Vector3f& p = row[u];
    const Eigen::Vector3f& l = row[u - 1];
    const Eigen::Vector3f& r = row[u + 1];
    if (std::isnan(p.x()) || std::isnan(l.x()) || std::isnan(r.x())) continue;
    const float depth2 = (p - g.eye).squaredNorm();
    if (!(depth2 > 0.0f)) continue;
    const float residual = (p - (l + r) * 0.5f).norm() / depth2;
    const int bin = residual < kRange ? static_cast<int>(residual * (kBins / kRange)) : kBins;
    ++h[static_cast<std::size_t>(bin)];
  }
}

}  // namespace

float estimate_noise_per_depth2(const PointGrid& grid) {
  if (grid.width < 3 || grid.height < 1) return 0.0f;
  const int rows = (grid.height + kRowStep - 1) / kRowStep;
  const Histogram histogram = tbb::parallel_reduce(
      tbb::blocked_range<int>(0, rows, 16), Histogram{},
      [&](const tbb::blocked_range<int>& range, Histogram h) {
        for (int i = range.begin(); i != range.end(); ++i) add_row(grid, kRowStep * i, h);
        return h;
      },
      [](Histogram a, const Histogram& b) {
        for (std::size_t i = 0; i < a.size(); ++i) a[i] += b[i];
        return a;
      });
  std::uint64_t total = 0;
  for (std::uint32_t n : histogram) total += n;
  if (total < 500) return 0.0f;
  const std::uint64_t rank = (total * 9 + 9) / 10;  // the 90th percentile, rounded up
  std::uint64_t seen = 0;
  for (int bin = 0; bin <= kBins; ++bin) {
    seen += histogram[static_cast<std::size_t>(bin)];
    if (seen >= rank) return (static_cast<float>(bin) + 0.5f) * (kRange / kBins);
  }
  return kRange;
}

}  // namespace meshflow
