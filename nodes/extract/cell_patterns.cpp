#include "nodes/extract/cell_patterns.h"

#include <tbb/parallel_for.h>

#include "runtime/parallel.h"

namespace meshflow {

CellPatterns cell_patterns(const SparseGrid& grid, const DistanceField& field, float iso) {
  CellPatterns out;
  const std::size_t cells = grid.cells.size();
  out.pattern.resize(cells);
  tbb::parallel_for(std::size_t{0}, cells, [&](std::size_t i) {
    int p = 0;
    for (int c = 0; c < 8; ++c) {
      const std::uint32_t k = grid.cell_corners[i][static_cast<std::size_t>(c)];
      if (!field.valid[k]) {
        p = 0;
        break;
      }
      p |= (field.values[k] < iso ? 1 : 0) << c;
    }
    out.pattern[i] = static_cast<std::uint8_t>(p == 255 ? 0 : p);
  });
  out.active = parallel_select_indices(cells, [&](std::size_t i) { return out.pattern[i] != 0; });
  return out;
}

}  // namespace meshflow
