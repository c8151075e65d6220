#pragma once
// The sparse voxel grid the voxelize stage builds and the distance and extract stages read:
// cells around the data and the corners they share.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "runtime/voxel_key.h"

namespace meshflow {

/// A box of cells, [lo, hi) per axis (cell indices as in cell_of()).
struct CellRange {
  Eigen::Vector3i lo = Eigen::Vector3i::Zero();
  Eigen::Vector3i hi = Eigen::Vector3i::Zero();
  /// Whether cell c lies in the box.
  bool contains(const Eigen::Vector3i& c) const {
    return (c.array() >= lo.array()).all() && (c.array() < hi.array()).all();
  }
};

/// Cells are addressed by the packed index of their minimum corner; corner c of a cell
/// (c = x + 2y + 4z, bits selecting +1 along each axis) is cell_corners[cell][c].
struct SparseGrid {
  float voxel_size = 0.0f;
  std::vector<VoxelKey> cells;                             ///< sorted, unique
  std::vector<VoxelKey> corners;                           ///< sorted, unique
  std::vector<std::array<std::uint32_t, 8>> cell_corners;  ///< indices into `corners`

  /// World position (metres) of corner i.
  Eigen::Vector3f corner_position(std::size_t i) const {
    return unpack_key(corners[i]).cast<float>() * voxel_size;
  }
  /// Index of the corner with integer index c, or UINT32_MAX if the grid lacks it. O(log n).
  std::uint32_t find_corner(const Eigen::Vector3i& c) const;
};

}  // namespace meshflow
