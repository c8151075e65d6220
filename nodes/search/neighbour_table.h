#pragma once
// The k nearest neighbours of every point of a set, found once and shared by the steps that
// need them (plane fits, orientation, normal interpolation).

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "nodes/search/spatial_index.h"
#include "runtime/default_init.h"

namespace meshflow {

/// Row i lists the (up to) k nearest points of point i, closest first; a point is its own
/// first neighbour. Rows are k wide; only the first counts[i] entries of a row are used.
struct NeighbourTable {
  std::size_t k = 0;
  /// size() * k; the entries of a row past its count are left uninitialised.
  UninitVector<std::uint32_t> indices;
  UninitVector<std::uint32_t> counts;  ///< one per point, min(k, number of points)

  /// Number of points (rows).
  std::size_t size() const { return counts.size(); }
  /// Row i: counts[i] neighbour indices, closest first.
  const std::uint32_t* row(std::size_t i) const { return indices.data() + i * k; }
};

/// The k nearest neighbours of every point of `positions` (finite, metres) through `index`
/// (built over `positions`). Parallel over points, deterministic; O(n k log n).
NeighbourTable build_neighbour_table(const std::vector<Eigen::Vector3f>& positions,
                                     const SpatialIndex& index, std::size_t k);

}  // namespace meshflow
