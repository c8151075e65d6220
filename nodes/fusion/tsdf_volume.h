#pragma once
// TSDF fusion of posed depth frames (KinectFusion-style, on CPU cores): the integrator, which
// writes frames into a map (tsdf_map.h) and owns the per-frame scratch, and TsdfVolume, a map
// with its integrator. Settings are fixed at construction, as voxblox's layer and integrator.

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "nodes/depth/depth_bounds_pyramid.h"
#include "nodes/fusion/integration_stats.h"
#include "nodes/fusion/tsdf_map.h"
#include "nodes/fusion/tsdf_ray_scratch.h"
#include "runtime/depth_frame.h"

namespace meshflow {

/// The estimator's 90th percentile is about 2 sigma of the noise; 1.5 x that is about 3 sigma.
constexpr float kBehindNoiseMultiple = 1.5f;

/// Fuses depth frames into a TsdfMap with its settings (TsdfConfig: the map's voxel size and
/// truncation, and the integration's band, integrator, carving and limits), fixed at
/// construction. Owns the per-frame scratch, kept across frames so that its capacity is reused.
/// Not thread-safe: one frame at a time.
class TsdfFrameIntegrator {
 public:
  /// Throws meshflow::Error unless behind_voxels is positive and finite (the map's own
  /// settings are checked by TsdfMap).
  explicit TsdfFrameIntegrator(const TsdfConfig& config);

  /// Fuses one depth frame (any depth format of DepthFrame; pixels <= 0 or NaN are ignored)
  /// seen from frame.T_world_camera into `map`: estimates the frame's depth noise, finds the
  /// blocks its band touches (the truncation in front of each measurement, config().
  /// behind_voxels' rule behind it; existing blocks looked up in parallel, new ones numbered in
  /// key order and zeroed in parallel), then updates those blocks in parallel, one task per
  /// block, as config().integrator says, and carves free space (config().carve_free_space).
  /// Voxels farther behind the measured depth than the band are left alone. Throws
  /// meshflow::Error, leaving the map unchanged, when the frame would add more than
  /// config().max_new_blocks_per_frame blocks or take the map past config().max_memory_bytes,
  /// for a pose with NaN entries, and for a map of another voxel size or truncation. The result
  /// does not depend on the number of threads. O(pixels + touched blocks x 512) projective;
  /// O(pixels x band voxels) along rays.
  IntegrationStats integrate(TsdfMap& map, const DepthFrame& frame);

  /// The settings it integrates with.
  const TsdfConfig& config() const { return config_; }

 private:
  // integrate()'s projective update of the touched blocks' voxels, with the frame's depth noise
  // estimate (estimate_noise_per_depth2()); returns the voxels updated.
  std::size_t update_blocks(TsdfMap& map, const std::vector<std::uint32_t>& touched,
                            const Image& depth, const DepthFrame& frame, float noise_per_depth2);
  // TsdfIntegrator::kAlongRay's phases after the band (tsdf_ray_integration.cpp); the blocks it
  // touched into touched_.
  void integrate_along_rays(TsdfMap& map, const DepthFrame& frame, const Image& depth,
                            IntegrationStats& stats);
  // config().carve_free_space's phase (tsdf_carving.cpp): in the blocks outside `touched` that
  // hold surface, the voxels in the frame's observed free space (band_pixels_) take
  // +truncation; counted in `stats`.
  void carve_free_blocks(TsdfMap& map, const DepthFrame& frame, const Image& depth,
                         const std::vector<std::uint32_t>& touched, IntegrationStats& stats);
  // Whether the frame's colour image can be fused with this depth image.
  bool fuses_color_of(const DepthFrame& frame, const Image& depth) const;

  TsdfConfig config_;
  std::vector<float> band_pixels_;   // per pixel of the last frame: depth, band behind (reused)
  std::vector<float> depth_slopes_;  // per pixel of the last frame: depth slopes (reused)
  std::vector<std::vector<std::uint64_t>> row_keys_;  // per image row: touched block keys (reused)
  // Per-frame scratch, kept so that its capacity is reused: the frame's depth in metres, the
  // touched blocks' keys and numbers, the along-ray integrator's lists.
  Image depth_m_;
  std::vector<VoxelKey> keys_;
  std::vector<std::uint32_t> touched_;
  RayScratch ray_scratch_;
  DepthBoundsPyramid depth_bounds_;         // of the last frame, for carving (reused)
  std::vector<std::uint8_t> touched_mark_;  // per block: touched by the last frame
};

/// A map with its integrator: what a fusion run holds. Everything that reads a map (the
/// mesher, the map file, the samplers) takes it as a `const TsdfMap&`.
class TsdfVolume : public TsdfMap {
 public:
  /// A new, empty map and its integrator with `config`. Throws meshflow::Error as TsdfMap and
  /// TsdfFrameIntegrator do.
  explicit TsdfVolume(const TsdfConfig& config = {});
  /// Adopts `map` (e.g. read_tsdf_map()) to fuse more frames with `config`'s integration
  /// settings; the map's own settings (voxel size, truncation, maximum weight, weighting,
  /// colour) are kept and override `config`'s.
  TsdfVolume(TsdfMap map, const TsdfConfig& config);

  /// Fuses one depth frame: TsdfFrameIntegrator::integrate() on this map. Not thread-safe
  /// against other calls on the same volume.
  IntegrationStats integrate(const DepthFrame& frame) {
    return integrator_.integrate(*this, frame);
  }
  /// The settings it was made with (the map's own ones as the map records them).
  const TsdfConfig& config() const { return integrator_.config(); }

 private:
  TsdfFrameIntegrator integrator_;
};

}  // namespace meshflow
