#include "nodes/voxelize/voxelize.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cassert>
#include <cmath>

#include "nodes/search/spatial_index.h"
#include "runtime/error.h"
#include "runtime/parallel.h"
#include "runtime/radix_sort.h"

namespace meshflow {
namespace {

// Keys relative to the bounding box of one grid, each axis just wide enough for the box (plus
// one step for corners). They sort in the same z, y, x order as packed keys but span far fewer
// bits, so the radix sorts need 2-3 passes instead of 6. Converted to packed keys at the end.
class CompactKeys {
 public:
  // Box of cell indices lo..hi (inclusive); throws if a corner of it cannot be packed.
  CompactKeys(const Eigen::Vector3i& lo, const Eigen::Vector3i& hi) : origin_(lo) {
    if (!cell_index_in_range(lo) || !cell_index_in_range(hi)) {
      throw Error("voxelize", "points",
                  "lie outside the grid's range (coordinates too large for the voxel size)");
    }
    for (int a = 0; a < 3; ++a) {
      const auto span = static_cast<std::uint32_t>(hi[a] - lo[a] + 2);  // + the corner step
      while ((std::uint32_t{1} << bits_[a]) < span) ++bits_[a];
    }
    shift_ = {0, bits_[0], bits_[0] + bits_[1]};
  }
  VoxelKey pack(const Eigen::Vector3i& c) const {
    const Eigen::Vector3i r = c - origin_;
    return (VoxelKey(r.z()) << shift_[2]) | (VoxelKey(r.y()) << shift_[1]) | VoxelKey(r.x());
  }
  Eigen::Vector3i unpack(VoxelKey k) const {
    Eigen::Vector3i r;
    for (int a = 0; a < 3; ++a)
      r[a] = static_cast<int>((k >> shift_[a]) & ((VoxelKey{1} << bits_[a]) - 1));
    return r + origin_;
  }
  /// Difference between the keys of neighbouring cells along `axis`.
  VoxelKey step(int axis) const { return VoxelKey{1} << shift_[axis]; }
  /// Rewrites sorted compact keys as (equally sorted) packed keys, in parallel.
  void to_packed(std::vector<VoxelKey>& keys) const {
    tbb::parallel_for(std::size_t{0}, keys.size(),
                      [&](std::size_t i) { keys[i] = pack_key(unpack(keys[i])); });
  }

 private:
  Eigen::Vector3i origin_;
  std::array<int, 3> bits_{0, 0, 0};
  std::array<int, 3> shift_{0, 0, 0};
};

// The compact key frame of the cells reached by every finite point of `cloud`.
CompactKeys compact_keys_for(const PointCloud& cloud, float voxel, float reach) {
  const Eigen::AlignedBox3f box = finite_bounds(cloud);
  if (box.isEmpty()) return CompactKeys(Eigen::Vector3i::Zero(), Eigen::Vector3i::Zero());
  const Eigen::Vector3f r = Eigen::Vector3f::Constant(reach);
  return CompactKeys(cell_of(box.min() - r, voxel), cell_of(box.max() + r, voxel));
}

// Flagged keys: a compact key shifted left by 3, its low bits saying "the block also spans
// the next cell along x (bit 0), y (bit 1), z (bit 2)". Sorting flagged keys sorts the keys.
constexpr int kFlagBits = 3;
constexpr VoxelKey kAllFlags = 7;

// Merges keys[i0, i1) with the flagged keys[j0, j1) shifted by `step` along their key part,
// appending to `out`. Both inputs are sorted; equal keys become one with OR-ed flags.
void merge_shifted(const std::vector<VoxelKey>& keys, std::size_t i0, std::size_t i1,
                   std::size_t j0, std::size_t j1, VoxelKey step, VoxelKey flag,
                   std::vector<VoxelKey>& out) {
  const VoxelKey none = ~VoxelKey{0};
  auto next_flagged = [&](std::size_t j) {
    while (j < j1 && (keys[j] & flag) == 0) ++j;
    return j;
  };
  std::size_t i = i0, j = next_flagged(j0);
  while (i < i1 || j < j1) {
    const VoxelKey a = i < i1 ? keys[i] >> kFlagBits : none;
    const VoxelKey b = j < j1 ? (keys[j] >> kFlagBits) + step : none;
    if (a <= b) {
      out.push_back(keys[i++] | (a == b ? keys[j] & kAllFlags : 0));
      if (a == b) j = next_flagged(j + 1);
    } else {
      out.push_back((b << kFlagBits) | (keys[j] & kAllFlags));
      j = next_flagged(j + 1);
    }
  }
}

// Sorted flagged keys with unique key parts -> the same keys plus, for each key flagged along
// `axis`, its neighbour one step further along `axis` (carrying the flags; flags of keys that
// meet are OR-ed). Shifting preserves order, so this is a linear merge, split into fixed blocks
// of the unshifted keys (each block takes the shifted keys falling into its key range) that are
// merged in parallel and concatenated in order.
std::vector<VoxelKey> dilate_along(const std::vector<VoxelKey>& keys, int axis,
                                   const CompactKeys& frame) {
  constexpr std::size_t kBlock = 16384;
  const VoxelKey step = frame.step(axis);
  const VoxelKey flag = VoxelKey{1} << axis;
  const std::size_t n = keys.size();
  const std::size_t blocks = std::max<std::size_t>(1, (n + kBlock - 1) / kBlock);
  // First shifted key at or after the key at index i (n for i == n).
  auto shifted_bound = [&](std::size_t i) -> std::size_t {
    if (i >= n) return n;
    const VoxelKey key = keys[i] >> kFlagBits;
    std::size_t lo = 0, hi = n;
    while (lo < hi) {
      const std::size_t mid = (lo + hi) / 2;
      if ((keys[mid] >> kFlagBits) + step < key)
        lo = mid + 1;
      else
        hi = mid;
    }
    return lo;
  };
  std::vector<std::vector<VoxelKey>> parts(blocks);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    const std::size_t i0 = b * kBlock, i1 = std::min(n, i0 + kBlock);
    const std::size_t j0 = b == 0 ? 0 : shifted_bound(i0);
    const std::size_t j1 = b + 1 == blocks ? n : shifted_bound(i1);
    parts[b].reserve(2 * (i1 - i0));
    merge_shifted(keys, i0, i1, j0, j1, step, flag, parts[b]);
  });
  return concatenate_parts(parts);
}

// Keys of flagged blocks, each dilated along the axes its flags name; flags dropped.
std::vector<VoxelKey> expand_blocks(std::vector<VoxelKey> flagged, const CompactKeys& frame) {
  for (int axis = 0; axis < 3; ++axis) flagged = dilate_along(flagged, axis, frame);
  tbb::parallel_for(std::size_t{0}, flagged.size(),
                    [&](std::size_t i) { flagged[i] >>= kFlagBits; });
  return flagged;
}

// For sorted cells shifted by `delta` (every shifted key and its +x neighbour present in the
// sorted corners), writes the corner index of each into column `column` of `out`, and that of
// its +x neighbour into column + 1: it directly follows (no key sorts between them). Linear walk.
void locate_corner_pair(const std::vector<VoxelKey>& cells, VoxelKey delta,
                        const std::vector<VoxelKey>& corners,
                        std::vector<std::array<std::uint32_t, 8>>& out, std::size_t column) {
  std::size_t j = 0;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const VoxelKey key = cells[i] + delta;
    while (corners[j] < key) ++j;
    assert(corners[j] == key);
    out[i][column] = static_cast<std::uint32_t>(j);
    out[i][column + 1] = static_cast<std::uint32_t>(j + 1);
  }
}

// Writes the keys of the cells lo..hi (inclusive, z-major) to out.
void write_cell_block(const Eigen::Vector3i& lo, const Eigen::Vector3i& hi, const CompactKeys& keys,
                      VoxelKey* out) {
  for (int z = lo.z(); z <= hi.z(); ++z)
    for (int y = lo.y(); y <= hi.y(); ++y)
      for (int x = lo.x(); x <= hi.x(); ++x) *out++ = keys.pack({x, y, z});
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
std::vector<VoxelKey> cells_by_enumeration(const PointCloud& cloud, float voxel, float reach,
                                           const CompactKeys& keys) {
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
    write_cell_block(ranges[i][0], ranges[i][1], keys, &cells[offsets[i]]);
  });
  radix_sort_unique(cells);
  return cells;
}

// For margins below one voxel a point's cube spans one or two cells along each axis: a block
// given by its lowest cell and three flags. The n flagged keys are sorted, blocks with the same
// lowest cell OR their flags, and the blocks are expanded by three separable merges. The result
// contains every cell of the exact union, plus the rare cells that combine the flags of
// different points with the same lowest cell (harmless: they touch those points' cubes).
std::vector<VoxelKey> cells_by_block_flags(const PointCloud& cloud, float voxel, float reach,
                                           const CompactKeys& frame) {
  // Neighbouring points (scan or pixel order) mostly share their block: each fixed block of
  // points drops repeats of the previous key before the sort.
  const std::size_t n = cloud.size();
  const std::size_t blocks = (n + kParallelBlock - 1) / kParallelBlock;
  std::vector<VoxelKey> keys(n);
  std::vector<std::size_t> counts(blocks);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    const std::size_t begin = b * kParallelBlock, end = std::min(n, begin + kParallelBlock);
    std::size_t out = begin;
    for (std::size_t i = begin; i < end; ++i) {
      const auto [lo, hi] = cell_range(cloud.positions[i], voxel, reach, i);
      VoxelKey flags = 0;
      for (int a = 0; a < 3; ++a) flags |= VoxelKey(hi[a] > lo[a] ? 1 : 0) << a;
      const VoxelKey key = (frame.pack(lo) << kFlagBits) | flags;
      if (out == begin || keys[out - 1] != key) keys[out++] = key;
    }
    counts[b] = out - begin;
  });
  std::vector<std::size_t> offsets = counts;
  std::vector<VoxelKey> flagged(exclusive_scan_in_place(offsets));
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    const auto first = keys.begin() + static_cast<std::ptrdiff_t>(b * kParallelBlock);
    std::copy(first, first + static_cast<std::ptrdiff_t>(counts[b]),
              flagged.begin() + static_cast<std::ptrdiff_t>(offsets[b]));
  });
  radix_sort_unique(flagged);
  // OR the flags of runs with the same key (serial, linear; runs are short).
  std::size_t out = 0;
  for (std::size_t i = 0; i < flagged.size(); ++i) {
    if (out > 0 && (flagged[out - 1] >> kFlagBits) == (flagged[i] >> kFlagBits))
      flagged[out - 1] |= flagged[i] & kAllFlags;
    else
      flagged[out++] = flagged[i];
  }
  flagged.resize(out);
  return expand_blocks(std::move(flagged), frame);
}

}  // namespace

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

  // 1. Cells overlapping each point's margin cube, as compact keys.
  const CompactKeys keys = compact_keys_for(cloud, config.voxel_size, reach);
  grid.cells = config.margin < 1.0f ? cells_by_block_flags(cloud, config.voxel_size, reach, keys)
                                    : cells_by_enumeration(cloud, config.voxel_size, reach, keys);

  // 2. Corners: each cell as a 2 x 2 x 2 block of corners (separable, linear merges).
  std::vector<VoxelKey> flagged(grid.cells.size());
  tbb::parallel_for(std::size_t{0}, flagged.size(),
                    [&](std::size_t i) { flagged[i] = (grid.cells[i] << kFlagBits) | kAllFlags; });
  grid.corners = expand_blocks(std::move(flagged), keys);

  // 3. Corner indices of each cell: one linear walk per pair of corners along x (0-1, 2-3, 4-5,
  // 6-7), the 4 walks in parallel.
  grid.cell_corners.resize(grid.cells.size());
  tbb::parallel_for(0, 4, [&](int pair) {
    const VoxelKey delta = ((pair & 1) ? keys.step(1) : 0) | ((pair & 2) ? keys.step(2) : 0);
    locate_corner_pair(grid.cells, delta, grid.corners, grid.cell_corners,
                       static_cast<std::size_t>(2 * pair));
  });
  keys.to_packed(grid.cells);
  keys.to_packed(grid.corners);
  return grid;
}

void keep_cells_in(SparseGrid& grid, const CellRange& range) {
  std::vector<std::uint8_t> used(grid.corners.size(), 0);
  std::size_t kept = 0;
  for (std::size_t i = 0; i < grid.cells.size(); ++i) {
    if (!range.contains(unpack_key(grid.cells[i]))) continue;
    grid.cells[kept] = grid.cells[i];
    grid.cell_corners[kept] = grid.cell_corners[i];
    for (std::uint32_t c : grid.cell_corners[kept]) used[c] = 1;
    ++kept;
  }
  grid.cells.resize(kept);
  grid.cell_corners.resize(kept);
  std::vector<std::uint32_t> renumbered(grid.corners.size());
  std::uint32_t next = 0;
  for (std::size_t c = 0; c < grid.corners.size(); ++c) {
    renumbered[c] = next;
    if (used[c]) grid.corners[next++] = grid.corners[c];
  }
  grid.corners.resize(next);
  for (auto& corners : grid.cell_corners)
    for (std::uint32_t& c : corners) c = renumbered[c];
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
