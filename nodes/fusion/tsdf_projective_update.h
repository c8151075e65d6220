#pragma once
// The projective TSDF update of one block (KinectFusion's and Open3D's rule, with each voxel's
// depth read at its exact projection): the kernel of TsdfFrameIntegrator's projective integration.
// Internal to nodes/fusion.

#include <cstddef>
#include <vector>

#include "nodes/fusion/tsdf_volume.h"
#include "runtime/image.h"

namespace meshflow {

/// Two neighbouring pixels lie on one surface when their depths differ by at most this many
/// pixel footprints (depth / fx): surfaces up to 80 degrees from facing the camera. Measured
/// (Redwood frames and the sphere orbit): 3 footprints gave 3.3335 mm / 4.42e-4 completeness, 6
/// gave 3.3232 mm / 3.34e-4, 8 gave 3.3217 mm / 3.19e-4; beyond that depth edges start to count.
constexpr float kSlopeFootprints = 6.0f;

/// The depth slope at each pixel, in metres per pixel along u and along v: the central
/// difference where both neighbours are valid and within `one_surface` x depth of the pixel (one
/// surface), else the one-sided difference to a neighbour that is, else 0. A voxel reads its
/// nearest pixel's depth corrected by the slope to its exact projection. `pixels`: (depth,
/// band) per pixel (band_pixels()). Layout: (depth, band, du, dv) per pixel, `pixels`' pair and
/// its slopes, so that a voxel reads all four at once. Parallel over rows; O(pixels).
void depth_slopes(const std::vector<float>& pixels, int width, int height, float one_surface,
                  std::vector<float>& slopes);

/// One frame's view of the map's voxels.
struct BlockUpdate {
  const float* pixels;  ///< per pixel: depth, band behind it (metres; depth 0 = invalid)
  int width, height;    ///< of the depth image
  /// per pixel: depth, band (as `pixels`) and depth slopes along u and v (depth_slopes()), or
  /// null: no slopes
  const float* slopes;
  const Image* color;  ///< RGB8 of the depth's size, or null: no colour fused
  const PinholeIntrinsics& intrinsics;
  Eigen::Isometry3f T_camera_world;
  const TsdfConfig& config;
  /// kBehindNoiseMultiple x the frame's estimate_noise_per_depth2() (1/m): with the least band
  /// (config.behind_voxels), how far behind its measured depth a pixel updates voxels that
  /// earlier frames observed (update_block()).
  float noise_band_per_depth2 = 0.0f;
};

/// Every voxel of a block in the frame's camera: depth z (metres) and image position (uf, vf),
/// voxel i = x + 8 y + 64 z, 8-wide along x (one vector per voxel row; AVX2 where the CPU has it).
struct BlockProjection {
  alignas(32) float z[kTsdfBlockVoxels];
  alignas(32) float u[kTsdfBlockVoxels];
  alignas(32) float v[kTsdfBlockVoxels];
};

/// Fills `out` for the block whose first voxel is `origin` (voxel units) as `frame`'s camera
/// sees it. Plain IEEE products and quotients (no FMA contraction), so every CPU gets the same
/// floats; AVX2 where the CPU has it. O(512).
void project_block(const Eigen::Vector3i& origin, const BlockUpdate& frame, BlockProjection& out);

/// Projects every voxel of the block into the frame and blends the truncated distance (and
/// colour) of the pixel it lands on into it; voxels outside the image, behind an invalid pixel or
/// farther behind the surface than its band keep their state. The band's widening beyond the
/// least band and the noise allowance (max(behind_voxels x voxel, noise_band_per_depth2 x
/// depth^2)) reaches only voxels no frame has observed (weight 0): it gives a grazing view's
/// cells corners behind the surface, while what other frames measured there — the far wall of a
/// narrow hole, the other side of a thin part — is not overwritten. Returns the voxels updated.
/// Reads only `frame`; safe on distinct blocks in parallel. O(512).
std::size_t update_block(TsdfBlock& block, const BlockUpdate& frame);

}  // namespace meshflow
