#pragma once
// Inside/outside corner patterns of the cells of a sparse grid, shared by the extraction methods.

#include <cstdint>
#include <vector>

#include "runtime/distance_field.h"
#include "runtime/sparse_grid.h"

namespace meshflow {

struct CellPatterns {
  /// Per cell: bit c set when corner c is inside (value < iso); 0 when the cell has an invalid
  /// corner or lies wholly on one side (nothing to extract).
  std::vector<std::uint8_t> pattern;
  std::vector<std::uint32_t> active;  ///< cells with pattern != 0, ascending
};

/// Parallel over cells, deterministic; O(cells).
CellPatterns cell_patterns(const SparseGrid& grid, const DistanceField& field, float iso);

}  // namespace meshflow
