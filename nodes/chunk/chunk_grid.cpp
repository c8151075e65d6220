#include "nodes/chunk/chunk_grid.h"

namespace meshflow::chunk {
namespace {

int floor_div(int a, int b) { return a / b - ((a % b != 0) && ((a < 0) != (b < 0)) ? 1 : 0); }

}  // namespace

Eigen::Vector3i ChunkGrid::chunk_of_cell(const Eigen::Vector3i& c) const {
  return {floor_div(c.x(), chunk_cells), floor_div(c.y(), chunk_cells),
          floor_div(c.z(), chunk_cells)};
}

CellRange ChunkGrid::owned_cells(const Eigen::Vector3i& k) const {
  CellRange range;
  range.lo = k * chunk_cells;
  range.hi = range.lo + Eigen::Vector3i::Constant(chunk_cells);
  return range;
}

void ChunkGrid::chunks_seeing_cell(const Eigen::Vector3i& c,
                                   std::vector<Eigen::Vector3i>& out) const {
  out.clear();
  const Eigen::Vector3i lo = chunk_of_cell(c - Eigen::Vector3i::Constant(overlap_cells));
  const Eigen::Vector3i hi = chunk_of_cell(c + Eigen::Vector3i::Constant(overlap_cells));
  for (int z = lo.z(); z <= hi.z(); ++z)
    for (int y = lo.y(); y <= hi.y(); ++y)
      for (int x = lo.x(); x <= hi.x(); ++x) out.emplace_back(x, y, z);
}

std::uint64_t morton_code(const Eigen::Vector3i& chunk) {
  std::uint64_t code = 0;
  for (int bit = 0; bit < 21; ++bit) {
    for (int axis = 0; axis < 3; ++axis) {
      const auto v = static_cast<std::uint64_t>(static_cast<std::int64_t>(chunk[axis]) + (1 << 20));
      code |= ((v >> bit) & 1u) << (3 * bit + axis);
    }
  }
  return code;
}

}  // namespace meshflow::chunk
