#pragma once
// The out-of-core path's partition of space: chunks of whole voxel cells on the global grid
// (cells of edge voxel_size with a corner at the origin, as voxelize() uses), each owning the
// cells of its box and seeing its points within an overlap of a few cells around it.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "runtime/sparse_grid.h"

namespace meshflow::chunk {

/// Chunk indices are cell indices divided by `chunk_cells` (rounded down), per axis.
struct ChunkGrid {
  float voxel_size = 0.0f;  ///< metres
  int chunk_cells = 0;      ///< chunk edge in cells (>= 1)
  int overlap_cells = 0;    ///< points within this many cells of a chunk also go to it

  /// The chunk owning cell c. O(1).
  Eigen::Vector3i chunk_of_cell(const Eigen::Vector3i& c) const;
  /// The cells chunk k owns, [k * chunk_cells, (k + 1) * chunk_cells) per axis.
  CellRange owned_cells(const Eigen::Vector3i& k) const;
  /// The chunks whose owned cells, grown by overlap_cells, contain cell c (1 to 8 when the
  /// overlap is below a chunk; more for larger overlaps), appended to `out` (cleared first).
  void chunks_seeing_cell(const Eigen::Vector3i& c, std::vector<Eigen::Vector3i>& out) const;
};

/// Interleaved bits of the chunk index (offset to non-negative): sorting chunks by it walks
/// space along a Z-order curve, so neighbouring chunks are near in the order (static assignment
/// to ranks, cache-friendly stitching). O(1).
std::uint64_t morton_code(const Eigen::Vector3i& chunk);

}  // namespace meshflow::chunk
