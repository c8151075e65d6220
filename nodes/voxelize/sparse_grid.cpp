#include "nodes/voxelize/sparse_grid.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>

#include "nodes/normals/spatial_index.h"
#include "runtime/error.h"

namespace meshflow {
namespace {

void sort_unique(std::vector<VoxelKey>& keys) {
  tbb::parallel_sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
}

// Keys of `cells` shifted by every offset in [lo, hi]^3 (per axis), sorted and unique.
std::vector<VoxelKey> expand(const std::vector<VoxelKey>& cells, int lo, int hi) {
  const int side = hi - lo + 1;
  const std::size_t per_cell = static_cast<std::size_t>(side * side * side);
  std::vector<VoxelKey> out(cells.size() * per_cell);
  tbb::parallel_for(std::size_t{0}, cells.size(), [&](std::size_t i) {
    const Eigen::Vector3i c = unpack_key(cells[i]);
    std::size_t at = i * per_cell;
    for (int dz = lo; dz <= hi; ++dz)
      for (int dy = lo; dy <= hi; ++dy)
        for (int dx = lo; dx <= hi; ++dx) out[at++] = pack_key(c + Eigen::Vector3i(dx, dy, dz));
  });
  sort_unique(out);
  return out;
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
  const int dilation = std::max(0, std::min(config.dilation, 4));
  SparseGrid grid;
  grid.voxel_size = config.voxel_size;
  std::vector<VoxelKey> occupied(cloud.size());
  tbb::parallel_for(std::size_t{0}, cloud.size(), [&](std::size_t i) {
    const Eigen::Vector3i c = cell_of(cloud.positions[i], config.voxel_size);
    if (!cell_index_in_range(c - Eigen::Vector3i::Constant(dilation)) ||
        !cell_index_in_range(c + Eigen::Vector3i::Constant(dilation + 1))) {
      throw Error("voxelize", "point " + std::to_string(i),
                  "lies outside the grid's range for a voxel size of " +
                      std::to_string(config.voxel_size) + " m (coordinates too large or not finite)");
    }
    occupied[i] = pack_key(c);
  });
  sort_unique(occupied);
  grid.cells = dilation > 0 ? expand(occupied, -dilation, dilation) : std::move(occupied);
  grid.corners = expand(grid.cells, 0, 1);
  grid.cell_corners.resize(grid.cells.size());
  tbb::parallel_for(std::size_t{0}, grid.cells.size(), [&](std::size_t i) {
    const Eigen::Vector3i c = unpack_key(grid.cells[i]);
    for (int k = 0; k < 8; ++k) {
      grid.cell_corners[i][static_cast<std::size_t>(k)] =
          grid.find_corner(c + Eigen::Vector3i(k & 1, (k >> 1) & 1, (k >> 2) & 1));
    }
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
  std::nth_element(spacing.begin(), spacing.begin() + static_cast<std::ptrdiff_t>(samples / 2), spacing.end());
  const float median = spacing[samples / 2];
  const float diagonal = finite_bounds(cloud).diagonal().norm();
  return std::max(factor * median, diagonal / 2000.0f);
}

}  // namespace meshflow
