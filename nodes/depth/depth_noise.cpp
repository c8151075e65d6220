#include "nodes/depth/depth_noise.h"

#include <cassert>
#include <cmath>
#include <cstddef>

namespace meshflow {

void ResidualHistogram::add(float residual) {
  const int bin = residual < kRange ? static_cast<int>(residual * (kBins / kRange)) : kBins;
  ++bins_[static_cast<std::size_t>(bin)];
}

void ResidualHistogram::merge(const ResidualHistogram& other) {
  for (std::size_t i = 0; i < bins_.size(); ++i) bins_[i] += other.bins_[i];
}

float ResidualHistogram::percentile90() const {
  std::uint64_t total = 0;
  for (std::uint32_t n : bins_) total += n;
  if (total < 500) return 0.0f;
  const std::uint64_t rank = (total * 9 + 9) / 10;  // the 90th percentile, rounded up
  std::uint64_t seen = 0;
  for (int bin = 0; bin <= kBins; ++bin) {
    seen += bins_[static_cast<std::size_t>(bin)];
    if (seen >= rank) return (static_cast<float>(bin) + 0.5f) * (kRange / kBins);
  }
  return kRange;
}

float estimate_noise_per_depth2(const Image& depth_m) {
  assert(depth_m.format() == PixelFormat::F32);
  if (depth_m.cols() < 3 || depth_m.rows() < 1) return 0.0f;
  return residual_percentile(depth_m.rows(), [&](int v, ResidualHistogram& h) {
    const float* row = depth_m.ptr<float>(v);
    for (int u = 1; u + 1 < depth_m.cols(); u += kNoiseColumnStep) {
      const float d = row[u], l = row[u - 1], r = row[u + 1];
      if (!(d > 0.0f && l > 0.0f && r > 0.0f) || !std::isfinite(d + l + r)) continue;
      h.add(std::abs(d - 0.5f * (l + r)) / (d * d));
    }
  });
}

}  // namespace meshflow
