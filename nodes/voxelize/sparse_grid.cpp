#include "nodes/voxelize/sparse_grid.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cassert>
#include <cmath>

#include "nodes/normals/spatial_index.h"
#include "runtime/error.h"
#include "runtime/parallel.h"
#include "runtime/radix_sort.h"

namespace meshflow {
namespace {

// Sorted union of sorted `keys` and the same keys shifted by `delta` (a one-cell step along one
// axis; shifting preserves the order of packed keys). Linear.
std::vector<VoxelKey> union_with_shift(const std::vector<VoxelKey>& keys, VoxelKey delta) {
  std::vector<VoxelKey> out;
  out.reserve(keys.size() * 2);
  std::size_t i = 0, j = 0;
  const std::size_t n = keys.size();
  while (i < n || j < n) {
    const VoxelKey a = i < n ? keys[i] : ~VoxelKey{0};
    const VoxelKey b = j < n ? keys[j] + delta : ~VoxelKey{0};
    const VoxelKey next = std::min(a, b);
    if (out.empty() || out.back() != next) out.push_back(next);
    if (a == next) ++i;
    if (b == next) ++j;
  }
  return out;
}

// For sorted `subset` shifted by `delta` (every shifted key present in sorted `superset`),
// writes the superset index of each into column `column` of `out`. Linear walk.
void locate_shifted(const std::vector<VoxelKey>& subset, VoxelKey delta,
                    const std::vector<VoxelKey>& superset,
                    std::vector<std::array<std::uint32_t, 8>>& out, std::size_t column) {
  std::size_t j = 0;
  for (std::size_t i = 0; i < subset.size(); ++i) {
    const VoxelKey key = subset[i] + delta;
    while (superset[j] < key) ++j;
    assert(superset[j] == key);
    out[i][column] = static_cast<std::uint32_t>(j);
  }
}

}  // namespace

std::uint32_t SparseGrid::find_corner(const Eigen::Vector3i& c) const {
  const VoxelKey key = pack_key(c);
  const auto it = std::lower_bound(corners.begin(), corners.end(), key);
  return it != corners.end() && *it == key ? static_cast<std::uint32_t>(it - corners.begin())
                                           : UINT32_MAX;
}

SparseGrid voxelize(const PointCloud& cloud, const VoxelizeConfig& config) {
  if (!(config.voxel_size > 0.0f) || !std::isfinite(config.voxel_size)) {
    throw Error("voxelize", "voxel_size", "must be a positive number of metres");
  }
  if (!(config.margin >= 0.0f && config.margin <= 2.0f)) {
    throw Error("voxelize", "margin", "must be between 0 and 2 voxels");
  }
  SparseGrid grid;
  grid.voxel_size = config.voxel_size;
  const float reach = config.margin * config.voxel_size;

  // 1. Cells overlapping each point's margin cube: count, prefix sum, fill, sort, unique.
  const std::size_t n = cloud.size();
  std::vector<std::uint32_t> offsets(n);
  std::vector<std::array<Eigen::Vector3i, 2>> ranges(n);
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    const Eigen::Vector3f& p = cloud.positions[i];
    const Eigen::Vector3i lo = cell_of(p - Eigen::Vector3f::Constant(reach), config.voxel_size);
    const Eigen::Vector3i hi = cell_of(p + Eigen::Vector3f::Constant(reach), config.voxel_size);
    if (!p.allFinite() || !cell_index_in_range(lo) || !cell_index_in_range(hi)) {
      throw Error("voxelize", "point " + std::to_string(i),
                  "lies outside the grid's range for a voxel size of " +
                      std::to_string(config.voxel_size) +
                      " m (coordinates too large or not finite)");
    }
    ranges[i] = {lo, hi};
    const Eigen::Vector3i span = hi - lo + Eigen::Vector3i::Ones();
    offsets[i] = static_cast<std::uint32_t>(span.prod());
  });
  grid.cells.resize(exclusive_scan_in_place(offsets));
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    const auto& [lo, hi] = ranges[i];
    std::uint32_t at = offsets[i];
    for (int z = lo.z(); z <= hi.z(); ++z)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int x = lo.x(); x <= hi.x(); ++x) grid.cells[at++] = pack_key({x, y, z});
  });
  radix_sort_unique(grid.cells);

  // 2. Corners: the cells dilated by one step in +x, +y and +z (separable, linear merges).
  grid.corners = grid.cells;
  for (int axis = 0; axis < 3; ++axis) {
    grid.corners = union_with_shift(grid.corners, VoxelKey{1} << (axis * kKeyBitsPerAxis));
  }

  // 3. Corner indices of each cell: one linear walk per corner offset, the 8 walks in parallel.
  grid.cell_corners.resize(grid.cells.size());
  tbb::parallel_for(0, 8, [&](int k) {
    const VoxelKey delta = (VoxelKey(k & 1)) | (VoxelKey((k >> 1) & 1) << kKeyBitsPerAxis) |
                           (VoxelKey((k >> 2) & 1) << (2 * kKeyBitsPerAxis));
    locate_shifted(grid.cells, delta, grid.corners, grid.cell_corners, static_cast<std::size_t>(k));
  });
  return grid;
}

float suggest_voxel_size(const PointCloud& cloud, const SpatialIndex& index, float factor) {
  const std::size_t n = cloud.size();
  if (n < 2) return 0.05f;
  const std::size_t samples = std::min<std::size_t>(n, 2000);
  std::vector<float> spacing(samples);
  tbb::parallel_for(std::size_t{0}, samples, [&](std::size_t s) {
    std::uint32_t idx[2];
    float d2[2];
    const std::size_t i = s * n / samples;
    index.knn(cloud.positions[i], 2, idx, d2);
    spacing[s] = std::sqrt(d2[1]);
  });
  std::nth_element(spacing.begin(), spacing.begin() + static_cast<std::ptrdiff_t>(samples / 2),
                   spacing.end());
  const float median = spacing[samples / 2];
  const float diagonal = finite_bounds(cloud).diagonal().norm();
  return std::max(factor * median, diagonal / 2000.0f);
}

}  // namespace meshflow
