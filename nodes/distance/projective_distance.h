#pragma once
// Projective signed distance from one depth image: for each grid corner, the measured depth
// along its pixel ray minus the corner's own depth (as in KinectFusion-style mapping). No
// nearest-neighbour search; the zero level is exactly where the corners' rays meet the surface.

#include "runtime/image.h"

#include "runtime/depth_frame.h"
#include "runtime/distance_field.h"
#include "runtime/sparse_grid.h"

namespace meshflow {

struct ProjectiveDistanceConfig {
  /// Corners whose |measured - own depth| exceeds this many voxels are invalid (behind the
  /// surface they are unobserved; far in front they carry no surface).
  float truncation_voxels = 3.0f;
};

/// Signed distances (metres, positive between camera and surface) at the corners of `grid`.
/// `depth_m`: filtered depth in metres (F32, 0 = invalid) with `intrinsics`, seen from
/// `T_world_camera`. Depth is interpolated bilinearly when the 4 surrounding pixels are valid
/// and within 5 % of each other, else taken from the nearest pixel. Corners projecting outside
/// the image or onto invalid pixels are invalid. `depth_m` must be F32 (asserted). Parallel
/// over corners; O(corners).
DistanceField projective_distance(const SparseGrid& grid, const Image& depth_m,
                                  const PinholeIntrinsics& intrinsics,
                                  const Eigen::Isometry3f& T_world_camera,
                                  const ProjectiveDistanceConfig& config = {});

}  // namespace meshflow
