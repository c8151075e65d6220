#include "nodes/fusion/tsdf_band.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "runtime/simd.h"

namespace meshflow {
namespace {

// tan of the angle between the ray through pixel (u, v) and the surface normal, from the depth
// two pixels either side on the same surface (one side where the other is unmeasured or across
// a depth jump): the length of the depth gradient along the row and the column, at most
// kMaxSlope; an axis where no neighbour qualifies (a silhouette: the surface turns away from
// the camera) counts kMaxSlope.
constexpr float kMaxSlope = 4.0f;  // 76 degrees
// A relative depth difference beyond the occlusion-edge filter's default (depth_filter.h): the
// neighbour is another surface, and a flying pixel between the two must not widen the band.
constexpr float kSameSurfaceJump = 0.06f;
float surface_slope(const Image& depth, int u, int v, float focal) {
  const float* pixels = depth.ptr<float>(0);  // rows contiguous (Image::row_bytes())
  const int width = depth.cols(), height = depth.rows();
  const float d = pixels[static_cast<std::size_t>(v) * static_cast<std::size_t>(width) +
                         static_cast<std::size_t>(u)];
  const float pixel = d / focal;  // metres per pixel at this depth
  auto axis_slope = [&](int du, int dv) {
    auto at = [&](int k) {
      const int x = u + k * du, y = v + k * dv;
      if (x < 0 || y < 0 || x >= width || y >= height) return 0.0f;
      const float z = pixels[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                             static_cast<std::size_t>(x)];
      const bool same_surface = z > 0.0f && std::abs(z - d) <= kSameSurfaceJump * d;
      return same_surface ? z : 0.0f;  // false for NaN too
    };
    const float before = at(-2), after = at(2);
    if (before > 0.0f && after > 0.0f) return std::abs(after - before) / (4.0f * pixel);
    if (after > 0.0f) return std::abs(after - d) / (2.0f * pixel);
    if (before > 0.0f) return std::abs(d - before) / (2.0f * pixel);
    return kMaxSlope;
  };
  const float along_row = axis_slope(1, 0), along_column = axis_slope(0, 1);
  return std::min(kMaxSlope, std::sqrt(along_row * along_row + along_column * along_column));
}

// Pixel (u, v)'s band (tsdf_band.h's rule) one pixel at a time; `row` is its row's output.
struct BandRule {
  float least, across, focal, noise_scale, truncation;

  void pixel(const Image& depth_m, int u, int v, float* row) const {
    const float d = depth_m.ptr<float>(v)[u];
    if (!(d > 0.0f) || !std::isfinite(d)) {
      row[2 * u] = row[2 * u + 1] = 0.0f;
      return;
    }
    const float slope = surface_slope(depth_m, u, v, focal);
    const float along_ray = std::max(least, across * std::sqrt(1.0f + slope * slope));
    const float noise = noise_scale * d * d;
    row[2 * u] = d;
    row[2 * u + 1] = std::min(truncation, std::max(along_ray, noise));
  }
};

using simd::Floats8;
using simd::Ints8;

// |x| as std::abs does it: the sign bit cleared.
#define MESHFLOW_BAND_ABS(x) reinterpret_cast<Floats8>(reinterpret_cast<Ints8>(x) & 0x7fffffff)

// BandRule::pixel() for the eight pixels u0 .. u0 + 7 of row v, 2 <= u0 and u0 + 9 < width (their
// neighbours two pixels along the row exist), as vectors: each lane exactly that arithmetic
// (IEEE quotients and square roots, the same comparisons, no FMA contraction). `up` / `down`:
// the rows two above and below (null past the image's edge).
MESHFLOW_AVX2_CLONES void band_of_eight(const BandRule& rule, const float* here, const float* up,
                                        const float* down, int u0, float* row) {
  Floats8 d, left, right, above{}, below{};
  __builtin_memcpy(&d, here + u0, sizeof d);
  __builtin_memcpy(&left, here + u0 - 2, sizeof left);
  __builtin_memcpy(&right, here + u0 + 2, sizeof right);
  if (up != nullptr) __builtin_memcpy(&above, up + u0, sizeof above);
  if (down != nullptr) __builtin_memcpy(&below, down + u0, sizeof below);
  const Floats8 inf = Floats8{} + std::numeric_limits<float>::infinity();
  const Ints8 valid = (d > 0.0f) & (d < inf);  // positive and finite
  const Floats8 pixel = d / rule.focal;
  const Floats8 jump = kSameSurfaceJump * d;
  const Floats8 zero{}, max_slope = Floats8{} + kMaxSlope;
  // A neighbour on d's surface, else 0 (NaN and infinity too).
  const auto same = [&](Floats8& z) {
    z = ((z > 0.0f) & (MESHFLOW_BAND_ABS(z - d) <= jump)) ? z : zero;
  };
  same(left);
  same(right);
  same(above);
  same(below);
  Floats8 slope[2];
  const Floats8* before[2] = {&left, &above};
  const Floats8* after[2] = {&right, &below};
  for (int axis = 0; axis < 2; ++axis) {
    const Floats8 b = *before[axis], a = *after[axis];
    const Ints8 has_b = b > 0.0f, has_a = a > 0.0f;
    const Floats8 both = MESHFLOW_BAND_ABS(a - b) / (4.0f * pixel);
    const Floats8 only_a = MESHFLOW_BAND_ABS(a - d) / (2.0f * pixel);
    const Floats8 only_b = MESHFLOW_BAND_ABS(d - b) / (2.0f * pixel);
    slope[axis] = (has_b & has_a) ? both : (has_a ? only_a : (has_b ? only_b : max_slope));
  }
  Floats8 length2 = slope[0] * slope[0] + slope[1] * slope[1];
  length2 = valid ? length2 : zero;
  Floats8 length;
  for (int j = 0; j < 8; ++j) length[j] = std::sqrt(length2[j]);
  const Floats8 s = length < kMaxSlope ? length : max_slope;  // std::min(kMaxSlope, length)
  const Floats8 secant2 = 1.0f + s * s;
  Floats8 secant;
  for (int j = 0; j < 8; ++j) secant[j] = std::sqrt(secant2[j]);
  const Floats8 wide = rule.across * secant;
  const Floats8 along_ray = rule.least < wide ? wide : Floats8{} + rule.least;
  const Floats8 noise = rule.noise_scale * d * d;
  const Floats8 widest = along_ray < noise ? noise : along_ray;
  const Floats8 band = widest < rule.truncation ? widest : Floats8{} + rule.truncation;
  for (int j = 0; j < 8; ++j) {
    row[2 * (u0 + j)] = valid[j] != 0 ? d[j] : 0.0f;
    row[2 * (u0 + j) + 1] = valid[j] != 0 ? band[j] : 0.0f;
  }
}

#undef MESHFLOW_BAND_ABS

}  // namespace

void band_pixels(const Image& depth_m, const PinholeIntrinsics& intrinsics,
                 const TsdfConfig& config, float noise_per_depth2, std::vector<float>& pixels) {
  const int width = depth_m.cols(), height = depth_m.rows();
  pixels.resize(2 * static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  const BandRule rule{config.behind_voxels * config.voxel_size,  // least
                      config.voxel_size,  // across: at least one voxel across the surface
                      0.5f * (intrinsics.fx + intrinsics.fy),
                      kBehindNoiseMultiple * noise_per_depth2, config.truncation()};
  tbb::parallel_for(0, height, [&](int v) {
    float* row = pixels.data() + 2 * static_cast<std::size_t>(v) * static_cast<std::size_t>(width);
    const float* here = depth_m.ptr<float>(v);
    const float* up = v >= 2 ? depth_m.ptr<float>(v - 2) : nullptr;
    const float* down = v + 2 < height ? depth_m.ptr<float>(v + 2) : nullptr;
    int u = 0;
    for (; u < std::min(2, width); ++u) rule.pixel(depth_m, u, v, row);
    for (; u + 9 < width; u += 8) band_of_eight(rule, here, up, down, u, row);
    for (; u < width; ++u) rule.pixel(depth_m, u, v, row);
  });
}

}  // namespace meshflow
