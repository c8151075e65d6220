#include "nodes/fusion/tsdf_projective_update.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "nodes/fusion/tsdf_band.h"
#include "runtime/simd.h"

namespace meshflow {

void depth_slopes(const std::vector<float>& pixels, int width, int height, float one_surface,
                  std::vector<float>& slopes) {
  const auto w = static_cast<std::size_t>(width);
  slopes.resize(pixels.size());
  tbb::parallel_for(0, height, [&](int v) {
    const std::size_t row = static_cast<std::size_t>(v) * w;
    const float* here = pixels.data() + 2 * row;
    const float* above = v > 0 ? here - 2 * w : nullptr;
    const float* below = v + 1 < height ? here + 2 * w : nullptr;
    float* out = slopes.data() + 2 * row;
    // Half the difference across both neighbours on d's surface, the difference to the one that
    // is, or 0.
    const auto slope = [&](float before, float d, float after) {
      const float limit = one_surface * d;
      const bool b = before > 0.0f && std::abs(before - d) <= limit;
      const bool a = after > 0.0f && std::abs(after - d) <= limit;
      if (a && b) return 0.5f * (after - before);
      if (a) return after - d;
      if (b) return d - before;
      return 0.0f;
    };
    for (std::size_t u = 0; u < w; ++u) {
      const float d = here[2 * u];
      if (!(d > 0.0f)) {
        out[2 * u] = out[2 * u + 1] = 0.0f;
        continue;
      }
      out[2 * u] = slope(u > 0 ? here[2 * u - 2] : 0.0f, d, u + 1 < w ? here[2 * u + 2] : 0.0f);
      out[2 * u + 1] = slope(above ? above[2 * u] : 0.0f, d, below ? below[2 * u] : 0.0f);
    }
  });
}

namespace {

// project_block()'s body, built for AVX2 and for the baseline (the clones must stay in this
// translation unit: GCC keeps them local).
MESHFLOW_AVX2_CLONES void project_voxel_rows(const Eigen::Vector3i& origin,
                                             const BlockUpdate& frame, BlockProjection& out) {
  static_assert(kTsdfBlockSide == 8, "one 8-wide vector per voxel row");
  const PinholeIntrinsics& k = frame.intrinsics;
  const float voxel = frame.config.voxel_size;
  const Eigen::Matrix3f r = frame.T_camera_world.linear();
  const Eigen::Vector3f base = frame.T_camera_world * (origin.cast<float>() * voxel);
  const Eigen::Vector3f step_x = r.col(0) * voxel, step_y = r.col(1) * voxel,
                        step_z = r.col(2) * voxel;
  const simd::Floats8 lanes = {0, 1, 2, 3, 4, 5, 6, 7};
  const simd::Floats8 dx = lanes * step_x.x(), dy = lanes * step_x.y(), dz = lanes * step_x.z();
  for (int z = 0; z < kTsdfBlockSide; ++z)
    for (int y = 0; y < kTsdfBlockSide; ++y) {
      const Eigen::Vector3f row =
          base + step_y * static_cast<float>(y) + step_z * static_cast<float>(z);
      const simd::Floats8 pz = row.z() + dz;
      const simd::Floats8 inv_z = 1.0f / pz;
      const simd::Floats8 uf = k.fx * (row.x() + dx) * inv_z + k.cx;
      const simd::Floats8 vf = k.fy * (row.y() + dy) * inv_z + k.cy;
      const std::size_t i = static_cast<std::size_t>(kTsdfBlockSide * (y + kTsdfBlockSide * z));
      __builtin_memcpy(out.z + i, &pz, sizeof pz);
      __builtin_memcpy(out.u + i, &uf, sizeof uf);
      __builtin_memcpy(out.v + i, &vf, sizeof vf);
    }
}

}  // namespace

void project_block(const Eigen::Vector3i& origin, const BlockUpdate& frame, BlockProjection& out) {
  project_voxel_rows(origin, frame, out);
}

std::size_t update_block(TsdfBlock& block, const BlockUpdate& frame) {
  const std::size_t width = static_cast<std::size_t>(frame.width);
  const float max_u = static_cast<float>(frame.width) - 0.5f;
  const float max_v = static_cast<float>(frame.height) - 0.5f;
  const float truncation = frame.config.truncation();
  BlockProjection projection;
  project_block(block.coords * kTsdfBlockSide, frame, projection);
  std::size_t count = 0;
  for (std::size_t i = 0; i < kTsdfBlockVoxels; ++i) {
    const float pz = projection.z[i];
    if (!(pz > 0.0f)) continue;
    const float uf = projection.u[i], vf = projection.v[i];
    if (!(uf > -0.5f && vf > -0.5f && uf < max_u && vf < max_v)) {
      continue;  // outside the image (or NaN)
    }
    const int u = static_cast<int>(uf + 0.5f), v = static_cast<int>(vf + 0.5f);
    const std::size_t pixel = static_cast<std::size_t>(v) * width + static_cast<std::size_t>(u);
    float d = frame.pixels[2 * pixel];  // 0 when invalid
    if (!(d > 0.0f)) continue;
    if (frame.slopes != nullptr)
      d += frame.slopes[2 * pixel] * (uf - static_cast<float>(u)) +
           frame.slopes[2 * pixel + 1] * (vf - static_cast<float>(v));
    const float sdf = d - pz;
    if (sdf < -frame.pixels[2 * pixel + 1]) continue;  // hidden behind the surface: unknown
    TsdfVoxel& vox = block.voxels[i];
    const float w = observation_weight(frame.config.weighting, d);
    const float total = vox.weight + w;
    const float inv_total = 1.0f / total;
    vox.distance = (vox.distance * vox.weight + std::min(sdf, truncation) * w) * inv_total;
    if (frame.color != nullptr) {
      const Rgb8 c = frame.color->at<Rgb8>(v, u);
      auto blend = [&](std::uint8_t old, std::uint8_t now) {
        return static_cast<std::uint8_t>(
            (static_cast<float>(old) * vox.weight + static_cast<float>(now) * w) * inv_total +
            0.5f);  // round to nearest: the value is >= 0
      };
      vox.color = Rgb8{blend(vox.color.r, c.r), blend(vox.color.g, c.g), blend(vox.color.b, c.b)};
    }
    vox.weight = std::min(total, frame.config.max_weight);
    ++count;
  }
  return count;
}

}  // namespace meshflow
