#pragma once
// The crossed cube edges of a sparse grid's active cells, one shared vertex each: the first
// half of every marching-cubes-style extraction (mc, pmc, emc).

#include "nodes/cube/cube_table.h"
#include "nodes/extract/cell_patterns.h"
#include "nodes/extract/edge_vertices.h"

namespace meshflow {

/// Segment of local cube edge e (0..11) of a cell with the given corners, in a 3-direction table.
inline std::size_t cube_edge_segment(const EdgeVertexTable& table,
                                     const std::array<std::uint32_t, 8>& corners, int e) {
  const auto& ce = kCubeEdges[static_cast<std::size_t>(e)];
  return table.segment(corners[static_cast<std::size_t>(ce[0])],
                       static_cast<std::size_t>(kCubeEdgeAxis[static_cast<std::size_t>(e)]));
}

/// Marks every grid edge crossed by the surface in some active cell (a table over the grid's
/// corners and the three axes). Parallel over active cells; O(active cells).
EdgeVertexTable mark_crossed_cube_edges(const SparseGrid& grid, const CellPatterns& cells);

}  // namespace meshflow
