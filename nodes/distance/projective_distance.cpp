#include "nodes/distance/projective_distance.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cassert>
#include <cmath>

namespace meshflow {
namespace {

// Depth at continuous pixel coordinates (x, y); 0 if there is no usable measurement.
float sample_depth(const Image& d, float x, float y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  if (x0 >= 0 && y0 >= 0 && x0 + 1 < d.cols() && y0 + 1 < d.rows()) {
    const float a = d.at<float>(y0, x0), b = d.at<float>(y0, x0 + 1);
    const float c = d.at<float>(y0 + 1, x0), e = d.at<float>(y0 + 1, x0 + 1);
    const float lo = std::min({a, b, c, e}), hi = std::max({a, b, c, e});
    if (lo > 0.0f && hi - lo < 0.05f * lo) {
      const float fx = x - static_cast<float>(x0), fy = y - static_cast<float>(y0);
      return (a * (1 - fx) + b * fx) * (1 - fy) + (c * (1 - fx) + e * fx) * fy;
    }
  }
  const int u = static_cast<int>(std::lround(x)), v = static_cast<int>(std::lround(y));
  if (u < 0 || v < 0 || u >= d.cols() || v >= d.rows()) return 0.0f;
  return d.at<float>(v, u);
}

}  // namespace

DistanceField projective_distance(const SparseGrid& grid, const Image& depth_m,
                                  const PinholeIntrinsics& k,
                                  const Eigen::Isometry3f& T_world_camera,
                                  const ProjectiveDistanceConfig& config) {
  assert(depth_m.format() == PixelFormat::F32 && "depth_m must be PixelFormat::F32 metres");
  const std::size_t n = grid.corners.size();
  const Eigen::Isometry3f T_camera_world = T_world_camera.inverse();
  const float truncation = config.truncation_voxels * grid.voxel_size;
  DistanceField field;
  field.values.assign(n, 0.0f);
  field.valid.assign(n, 0);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, n, 2048), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const Eigen::Vector3f p = T_camera_world * grid.corner_position(i);
          if (!(p.z() > 0.0f)) continue;
          const float x = k.fx * p.x() / p.z() + k.cx, y = k.fy * p.y() / p.z() + k.cy;
          const float measured = sample_depth(depth_m, x, y);
          if (!(measured > 0.0f)) continue;
          const float sdf = measured - p.z();
          if (std::abs(sdf) > truncation) continue;
          field.values[i] = sdf;
          field.valid[i] = 1;
        }
      });
  return field;
}

}  // namespace meshflow
