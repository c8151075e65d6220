#include "nodes/fusion/tsdf_band.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace meshflow {
namespace {

// band_pixels()' rule one pixel at a time, as it was before eight pixels went through vectors:
// the oracle the vector code must match bit for bit.
float slope_oracle(const Image& depth, int u, int v, float focal) {
  const int width = depth.cols(), height = depth.rows();
  const float d = depth.ptr<float>(v)[u];
  const float pixel = d / focal;
  auto axis_slope = [&](int du, int dv) {
    auto at = [&](int k) {
      const int x = u + k * du, y = v + k * dv;
      if (x < 0 || y < 0 || x >= width || y >= height) return 0.0f;
      const float z = depth.ptr<float>(y)[x];
      return z > 0.0f && std::abs(z - d) <= 0.06f * d ? z : 0.0f;
    };
    const float before = at(-2), after = at(2);
    if (before > 0.0f && after > 0.0f) return std::abs(after - before) / (4.0f * pixel);
    if (after > 0.0f) return std::abs(after - d) / (2.0f * pixel);
    if (before > 0.0f) return std::abs(d - before) / (2.0f * pixel);
    return 4.0f;
  };
  const float r = axis_slope(1, 0), c = axis_slope(0, 1);
  return std::min(4.0f, std::sqrt(r * r + c * c));
}

bool band_same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Depth with holes, NaN, infinity, negative values, jumps between surfaces and smooth slopes,
// in images whose widths leave every remainder after the vector blocks: each pixel's depth and
// band are the oracle's bits.
TEST(TsdfBand, BandPixelsMatchTheRuleOnePixelAtATime) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (const int width : {1, 3, 10, 11, 12, 17, 64, 70}) {
    const int height = 9;
    Image depth(height, width, PixelFormat::F32);
    for (int v = 0; v < height; ++v)
      for (int u = 0; u < width; ++u) {
        const float r = unit(rng);
        float z = 0.8f + 0.01f * static_cast<float>(u) + 0.03f * static_cast<float>(v) +
                  0.002f * unit(rng);
        if (r < 0.08f)
          z = 0.0f;
        else if (r < 0.1f)
          z = std::numeric_limits<float>::quiet_NaN();
        else if (r < 0.11f)
          z = std::numeric_limits<float>::infinity();
        else if (r < 0.12f)
          z = -1.0f;
        else if (r < 0.2f)
          z *= 1.5f;  // another surface
        depth.ptr<float>(v)[u] = z;
      }
    PinholeIntrinsics k;
    k.width = width;
    k.height = height;
    k.fx = 500.0f;
    k.fy = 510.0f;
    TsdfConfig config;
    config.voxel_size = 0.004f;
    const float noise = 0.002f;
    std::vector<float> pixels;
    band_pixels(depth, k, config, noise, pixels);
    ASSERT_EQ(pixels.size(), 2u * static_cast<std::size_t>(width * height));
    for (int v = 0; v < height; ++v)
      for (int u = 0; u < width; ++u) {
        const float d = depth.ptr<float>(v)[u];
        float want_d = 0.0f, want_band = 0.0f;
        if (d > 0.0f && std::isfinite(d)) {
          const float slope = slope_oracle(depth, u, v, 0.5f * (k.fx + k.fy));
          const float along = std::max(config.behind_voxels * config.voxel_size,
                                       config.voxel_size * std::sqrt(1.0f + slope * slope));
          want_d = d;
          want_band =
              std::min(config.truncation(), std::max(along, kBehindNoiseMultiple * noise * d * d));
        }
        const std::size_t p = static_cast<std::size_t>(v * width + u);
        ASSERT_TRUE(band_same_bits(pixels[2 * p], want_d) &&
                    band_same_bits(pixels[2 * p + 1], want_band))
            << "width " << width << " pixel (" << u << ", " << v << "): " << pixels[2 * p + 1]
            << " vs " << want_band;
      }
  }
}

}  // namespace
}  // namespace meshflow
