#include "runtime/sparse_grid.h"

#include <algorithm>

namespace meshflow {

std::uint32_t SparseGrid::find_corner(const Eigen::Vector3i& c) const {
  const VoxelKey key = pack_key(c);
  const auto it = std::lower_bound(corners.begin(), corners.end(), key);
  return it != corners.end() && *it == key ? static_cast<std::uint32_t>(it - corners.begin())
                                           : UINT32_MAX;
}

}  // namespace meshflow
