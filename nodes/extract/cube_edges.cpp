#include "nodes/extract/cube_edges.h"

#include <tbb/parallel_for.h>

namespace meshflow {

EdgeVertexTable mark_crossed_cube_edges(const SparseGrid& grid, const CellPatterns& cells) {
  EdgeVertexTable table(grid.corners.size(), 3);
  tbb::parallel_for(std::size_t{0}, cells.active.size(), [&](std::size_t a) {
    const std::uint32_t cell = cells.active[a];
    const auto& corners = grid.cell_corners[cell];
    const int pattern = cells.pattern[cell];
    for (int e = 0; e < 12; ++e) {
      const auto& ce = kCubeEdges[static_cast<std::size_t>(e)];
      if (((pattern >> ce[0]) & 1) == ((pattern >> ce[1]) & 1)) continue;
      table.mark(cube_edge_segment(table, corners, e), corners[static_cast<std::size_t>(ce[1])]);
    }
  });
  return table;
}

}  // namespace meshflow
