#include "nodes/fusion/tsdf_band.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

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

}  // namespace

void band_pixels(const Image& depth_m, const PinholeIntrinsics& intrinsics,
                 const TsdfConfig& config, float noise_per_depth2, std::vector<float>& pixels) {
  const std::size_t width = static_cast<std::size_t>(depth_m.cols());
  pixels.resize(2 * width * static_cast<std::size_t>(depth_m.rows()));
  const float least = config.behind_voxels * config.voxel_size;
  const float across = config.voxel_size;  // at least one voxel across the surface
  const float focal = 0.5f * (intrinsics.fx + intrinsics.fy);
  tbb::parallel_for(0, depth_m.rows(), [&](int v) {
    const float* depth_row = depth_m.ptr<float>(v);
    float* row = pixels.data() + 2 * static_cast<std::size_t>(v) * width;
    for (int u = 0; u < depth_m.cols(); ++u) {
      const float d = depth_row[u];
      if (!(d > 0.0f) || !std::isfinite(d)) {
        row[2 * u] = row[2 * u + 1] = 0.0f;
        continue;
      }
      const float slope = surface_slope(depth_m, u, v, focal);
      const float along_ray = std::max(least, across * std::sqrt(1.0f + slope * slope));
      const float noise = kBehindNoiseMultiple * noise_per_depth2 * d * d;
      row[2 * u] = d;
      row[2 * u + 1] = std::min(config.truncation(), std::max(along_ray, noise));
    }
  });
}

}  // namespace meshflow
