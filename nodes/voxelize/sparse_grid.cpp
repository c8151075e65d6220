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

// Writes the keys of the cells lo..hi (inclusive, z-major) to out.
void write_cell_block(const Eigen::Vector3i& lo, const Eigen::Vector3i& hi, VoxelKey* out) {
  for (int z = lo.z(); z <= hi.z(); ++z)
    for (int y = lo.y(); y <= hi.y(); ++y)
      for (int x = lo.x(); x <= hi.x(); ++x) *out++ = pack_key({x, y, z});
}

// Throws unless the cells from p - reach to p + reach can be packed.
std::array<Eigen::Vector3i, 2> cell_range(const Eigen::Vector3f& p, float voxel, float reach,
                                          std::size_t i) {
  const Eigen::Vector3i lo = cell_of(p - Eigen::Vector3f::Constant(reach), voxel);
  const Eigen::Vector3i hi = cell_of(p + Eigen::Vector3f::Constant(reach), voxel);
  if (!p.allFinite() || !cell_index_in_range(lo) || !cell_index_in_range(hi)) {
    throw Error("voxelize", "point " + std::to_string(i),
                "lies outside the grid's range for a voxel size of " + std::to_string(voxel) +
                    " m (coordinates too large or not finite)");
  }
  return {lo, hi};
}

// Exact union of the cells overlapping every point's cube (any margin): up to (2m+1)^3 keys per
// point, then radix sort + unique.
std::vector<VoxelKey> cells_by_enumeration(const PointCloud& cloud, float voxel, float reach) {
  const std::size_t n = cloud.size();
  std::vector<std::uint32_t> offsets(n);
  std::vector<std::array<Eigen::Vector3i, 2>> ranges(n);
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    ranges[i] = cell_range(cloud.positions[i], voxel, reach, i);
    offsets[i] =
        static_cast<std::uint32_t>((ranges[i][1] - ranges[i][0] + Eigen::Vector3i::Ones()).prod());
  });
  std::vector<VoxelKey> cells(exclusive_scan_in_place(offsets));
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    write_cell_block(ranges[i][0], ranges[i][1], &cells[offsets[i]]);
  });
  radix_sort_unique(cells);
  return cells;
}

// For margins below one voxel a point's cube reaches at most one cell beyond its own along
// each axis. Each point contributes its cell's key tagged with 6 bits (cube crosses the low /
// high face in x, y, z); after sort + unique the tags of a cell are OR-ed and the cell is
// expanded towards the tagged faces. n keys are sorted instead of up to 8n. The result contains
// every cell the exact union has, plus at most the few cells that combine the tags of different
// points of one cell (harmless: their corners are near data too).
std::vector<VoxelKey> cells_by_face_flags(const PointCloud& cloud, float voxel, float reach) {
  const std::size_t n = cloud.size();
  std::vector<std::uint64_t> tagged(n);
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    const auto [lo, hi] = cell_range(cloud.positions[i], voxel, reach, i);
    const Eigen::Vector3i c = cell_of(cloud.positions[i], voxel);
    std::uint64_t flags = 0;
    for (int a = 0; a < 3; ++a) {
      flags |= (lo[a] < c[a] ? 1u : 0u) << (2 * a);
      flags |= (hi[a] > c[a] ? 2u : 0u) << (2 * a);
    }
    tagged[i] = (pack_key(c) << 6) | flags;
  });
  radix_sort_unique(tagged);
  // OR the tags of each cell (runs of equal key), then count and emit the expanded cells.
  std::vector<std::pair<VoxelKey, std::uint32_t>> occupied;
  for (std::size_t i = 0; i < tagged.size(); ++i) {
    const VoxelKey key = tagged[i] >> 6;
    const auto flags = static_cast<std::uint32_t>(tagged[i] & 63u);
    if (occupied.empty() || occupied.back().first != key)
      occupied.emplace_back(key, flags);
    else
      occupied.back().second |= flags;
  }
  std::vector<std::uint32_t> offsets(occupied.size());
  tbb::parallel_for(std::size_t{0}, occupied.size(), [&](std::size_t i) {
    std::uint32_t count = 1;
    for (int a = 0; a < 3; ++a)
      count *=
          1 + ((occupied[i].second >> (2 * a)) & 1u) + ((occupied[i].second >> (2 * a + 1)) & 1u);
    offsets[i] = count;
  });
  std::vector<VoxelKey> cells(exclusive_scan_in_place(offsets));
  tbb::parallel_for(std::size_t{0}, occupied.size(), [&](std::size_t i) {
    const Eigen::Vector3i c = unpack_key(occupied[i].first);
    const std::uint32_t f = occupied[i].second;
    Eigen::Vector3i lo, hi;
    for (int a = 0; a < 3; ++a) {
      lo[a] = c[a] - static_cast<int>((f >> (2 * a)) & 1u);
      hi[a] = c[a] + static_cast<int>((f >> (2 * a + 1)) & 1u);
    }
    write_cell_block(lo, hi, &cells[offsets[i]]);
  });
  radix_sort_unique(cells);
  return cells;
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

  // 1. Cells overlapping each point's margin cube.
  grid.cells = config.margin < 1.0f ? cells_by_face_flags(cloud, config.voxel_size, reach)
                                    : cells_by_enumeration(cloud, config.voxel_size, reach);

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

namespace meshflow {

float suggest_voxel_size_for_depth(const PointCloud& cloud, float focal_px, float factor) {
  if (cloud.empty() || !(focal_px > 0.0f)) return 0.01f;
  const std::size_t samples = std::min<std::size_t>(cloud.size(), 2001);
  std::vector<float> range(samples);
  for (std::size_t s = 0; s < samples; ++s) {
    range[s] = (cloud.positions[s * cloud.size() / samples] - cloud.sensor_origin).norm();
  }
  std::nth_element(range.begin(), range.begin() + static_cast<std::ptrdiff_t>(samples / 2),
                   range.end());
  return factor * range[samples / 2] / focal_px;
}

}  // namespace meshflow
