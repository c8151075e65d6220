#pragma once
// What one depth frame says along each pixel's ray, shared by the TSDF integrators
// (tsdf_volume.h): the measured depth and the band behind it that a frame may update.

#include <vector>

#include "nodes/fusion/tsdf_volume.h"
#include "runtime/image.h"

namespace meshflow {

/// Fills `pixels` (resized to 2 x depth's pixels) with each pixel's depth in metres (0 where
/// invalid or not finite) and the band behind it along the ray (metres; the rule of
/// TsdfConfig::behind_voxels, with `noise_per_depth2` from estimate_noise_per_depth2()).
/// depth_m: a float depth image in metres. Parallel over rows; O(pixels).
void band_pixels(const Image& depth_m, const PinholeIntrinsics& intrinsics,
                 const TsdfConfig& config, float noise_per_depth2, std::vector<float>& pixels);

/// The weight of one observation at this depth (metres) under the scheme. O(1).
inline float observation_weight(TsdfWeighting scheme, float depth) {
  return scheme == TsdfWeighting::kInverseDepth ? 1.0f / (depth * depth) : 1.0f;
}

}  // namespace meshflow
