#pragma once
// The along-ray integrator's rays and per-frame lists (tsdf_ray_integration.cpp);
// TsdfFrameIntegrator keeps a RayScratch across frames so that the lists' capacity is reused.
// Internal to nodes/fusion.

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "runtime/voxel_key.h"

namespace meshflow {

/// Pixels of a tile whose points fall in one voxel, as one ray.
struct MergedRay {
  Eigen::Vector3f point_sum = Eigen::Vector3f::Zero();  ///< world metres
  std::array<float, 3> color_sum{};                     ///< RGB, 0..255
  float weight = 0.0f;                                  ///< sum of observation weights
  float band = 0.0f;                                    ///< behind the point, metres (largest)
  std::uint32_t pixels = 0;                             ///< merged pixels
  Eigen::Vector3i voxel;                                ///< the voxel nearest its pixels' points
};

/// A ray's segment in voxel units: from `truncation` in front of its mean point (not behind the
/// camera) to its band behind it, with the unit direction from the camera; and what the ray
/// blends into a voxel. Four-lane fields, so that the blend loop loads each with one instruction.
struct RaySegment {
  Eigen::Vector4f from, to, span;    ///< voxel units (x, y, z, 0); span = to - from
  Eigen::Vector4f point_band;        ///< mean point (voxel units), band behind it (voxel units)
  Eigen::Vector4f direction_weight;  ///< unit direction, the ray's weight (MergedRay::weight)
  Eigen::Vector4f color;             ///< mean RGB x weight, 0
};

/// A block a ray crosses.
struct RayBlock {
  VoxelKey block;     ///< pack_key() of its coordinates
  std::uint32_t ray;  ///< its number: index into RayScratch::segments
};

/// One frame's lists of the along-ray integration, cleared and refilled every frame.
struct RayScratch {
  std::vector<std::vector<MergedRay>> tile_row_rays;  ///< per row of 8 x 8 pixel tiles
  /// Per row of tiles r, its rays' segments from r x 8 x width on (a ray's number).
  std::unique_ptr<RaySegment[]> segments;
  std::size_t segment_capacity = 0;              ///< entries allocated in `segments`
  std::vector<std::vector<RayBlock>> row_pairs;  ///< (block, ray) per row of tiles
  std::vector<std::vector<VoxelKey>> row_keys;   ///< per row of tiles: its blocks' keys
  std::vector<RayBlock> pairs;                   ///< joined in ray order
  std::vector<std::uint32_t> pair_blocks;        ///< per pair: its block's position among the keys
  std::vector<std::uint32_t> block_rays;  ///< the pairs' rays by block, each block's in order
  std::vector<std::size_t> starts;        ///< per block: its first entry in block_rays
};

}  // namespace meshflow
