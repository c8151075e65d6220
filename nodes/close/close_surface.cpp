#include "nodes/close/close_surface.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <string>

#include "runtime/error.h"
#include "runtime/voxel_key.h"

namespace meshflow {
namespace {

// The [t0, t1] part of the segment o + t d (t in [0, t_end]) inside the box [lo, hi]; false
// when it misses.
bool clip_segment(const Eigen::Vector3f& o, const Eigen::Vector3f& d, float t_end,
                  const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, float& t0, float& t1) {
  t0 = 0.0f;
  t1 = t_end;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0f) {
      if (o[a] < lo[a] || o[a] > hi[a]) return false;
      continue;
    }
    float ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t0 <= t1;
}

// Marks the lattice nodes nearest to the samples (half a voxel apart) of each line of sight,
// from the sensor to `stop` metres before its point. Idempotent stores: any thread order
// marks the same nodes.
std::vector<std::uint8_t> seen_empty_nodes(const PointCloud& cloud, const Eigen::Vector3i& lo,
                                           const Eigen::Vector3i& size, float voxel, float stop) {
  const std::size_t nodes = static_cast<std::size_t>(size.x()) * size.y() * size.z();
  std::vector<std::atomic<std::uint8_t>> marks(nodes);
  for (auto& m : marks) m.store(0, std::memory_order_relaxed);
  const Eigen::Vector3f box_lo = lo.cast<float>() * voxel;
  const Eigen::Vector3f box_hi = (lo + size - Eigen::Vector3i::Ones()).cast<float>() * voxel;
  const Eigen::Vector3f o = cloud.sensor_origin;
  tbb::parallel_for(std::size_t{0}, cloud.size(), [&](std::size_t i) {
    const Eigen::Vector3f ray = cloud.positions[i] - o;
    const float length = ray.norm();
    if (!(length > stop)) return;
    const Eigen::Vector3f d = ray / length;
    float t0 = 0.0f, t1 = 0.0f;
    if (!clip_segment(o, d, length - stop, box_lo, box_hi, t0, t1)) return;
    const float step = 0.5f * voxel;
    // Counted steps: `t += step` stops moving once t / step passes 2^24 (a sensor tens of
    // kilometres away at centimetre voxels). The clipped segment is at most the box's diagonal.
    const auto steps = static_cast<std::int64_t>(std::floor((t1 - t0) / step));
    for (std::int64_t k = 0; k <= steps; ++k) {
      const float t = t0 + static_cast<float>(k) * step;
      const Eigen::Vector3f q = (o + t * d) / voxel;
      const Eigen::Vector3i c(static_cast<int>(std::lround(q.x())) - lo.x(),
                              static_cast<int>(std::lround(q.y())) - lo.y(),
                              static_cast<int>(std::lround(q.z())) - lo.z());
      if ((c.array() < 0).any() || (c.array() >= size.array()).any()) continue;
      marks[(static_cast<std::size_t>(c.z()) * size.y() + c.y()) * size.x() + c.x()].store(
          1, std::memory_order_relaxed);
    }
  });
  std::vector<std::uint8_t> out(nodes);
  for (std::size_t n = 0; n < nodes; ++n) out[n] = marks[n].load(std::memory_order_relaxed);
  return out;
}

// Cells of the lattice (lower corner key) whose 8 corners do not all have one sign, and that
// `existing` (sorted) lacks; sorted.
std::vector<VoxelKey> crossed_cells(const DiffusionLattice& l, const Eigen::Vector3i& lo,
                                    const std::vector<VoxelKey>& existing) {
  const Eigen::Vector3i n = l.size;
  std::vector<std::vector<VoxelKey>> per_plane(static_cast<std::size_t>(std::max(0, n.z() - 1)));
  tbb::parallel_for(0, n.z() - 1, [&](int z) {
    std::vector<VoxelKey>& out = per_plane[static_cast<std::size_t>(z)];
    for (int y = 0; y + 1 < n.y(); ++y) {
      for (int x = 0; x + 1 < n.x(); ++x) {
        int inside = 0;
        for (int c = 0; c < 8; ++c)
          inside += l.values[l.index(x + (c & 1), y + ((c >> 1) & 1), z + ((c >> 2) & 1))] < 0.0f;
        if (inside == 0 || inside == 8) continue;
        const VoxelKey key = pack_key(lo + Eigen::Vector3i(x, y, z));
        if (!std::binary_search(existing.begin(), existing.end(), key)) out.push_back(key);
      }
    }
  });
  std::vector<VoxelKey> cells;
  for (const auto& plane : per_plane) cells.insert(cells.end(), plane.begin(), plane.end());
  tbb::parallel_sort(cells.begin(), cells.end());
  return cells;
}

// A grid of the given sorted cells: their corners (sorted, unique) and each cell's corner
// indices.
SparseGrid grid_of_cells(std::vector<VoxelKey> cells, float voxel) {
  SparseGrid grid;
  grid.voxel_size = voxel;
  grid.cells = std::move(cells);
  std::vector<VoxelKey> corners(grid.cells.size() * 8);
  tbb::parallel_for(std::size_t{0}, grid.cells.size(), [&](std::size_t i) {
    const Eigen::Vector3i c = unpack_key(grid.cells[i]);
    for (int k = 0; k < 8; ++k)
      corners[i * 8 + static_cast<std::size_t>(k)] =
          pack_key(c + Eigen::Vector3i(k & 1, (k >> 1) & 1, (k >> 2) & 1));
  });
  tbb::parallel_sort(corners.begin(), corners.end());
  corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
  grid.corners = std::move(corners);
  grid.cell_corners.resize(grid.cells.size());
  tbb::parallel_for(std::size_t{0}, grid.cells.size(), [&](std::size_t i) {
    const Eigen::Vector3i c = unpack_key(grid.cells[i]);
    for (int k = 0; k < 8; ++k)
      grid.cell_corners[i][static_cast<std::size_t>(k)] =
          grid.find_corner(c + Eigen::Vector3i(k & 1, (k >> 1) & 1, (k >> 2) & 1));
  });
  return grid;
}

}  // namespace

ClosedDistance close_distance_field(const SparseGrid& grid, const DistanceField& field,
                                    const PointCloud& cloud, const CloseConfig& config,
                                    CloseReport* report) {
  CloseReport r;
  ClosedDistance out;
  const float voxel = grid.voxel_size;
  if (grid.corners.empty() || field.valid_count() == 0) {
    out.grid = grid;
    out.distance = field;
    if (report != nullptr) *report = r;
    return out;
  }
  // 1. The lattice: the grid's corners grown by the margin.
  Eigen::Vector3i lo = unpack_key(grid.corners.front()), hi = lo;
  for (VoxelKey k : grid.corners) {
    const Eigen::Vector3i c = unpack_key(k);
    lo = lo.cwiseMin(c);
    hi = hi.cwiseMax(c);
  }
  const int margin = std::max(1, static_cast<int>(std::ceil(config.margin_voxels)));
  lo.array() -= margin;
  hi.array() += margin;
  DiffusionLattice lattice;
  lattice.size = hi - lo + Eigen::Vector3i::Ones();
  const double corners =
      static_cast<double>(lattice.size.x()) * lattice.size.y() * lattice.size.z();
  if (corners > static_cast<double>(config.max_lattice_corners))
    throw Error("close", "lattice",
                std::to_string(lattice.size.x()) + " x " + std::to_string(lattice.size.y()) +
                    " x " + std::to_string(lattice.size.z()) + " corners of " +
                    std::to_string(voxel) + " m exceed the limit of " +
                    std::to_string(config.max_lattice_corners) +
                    " for --close; expected a bounded object: use a larger --voxel or --crop");
  r.lattice = lattice.size;
  const float outside = static_cast<float>(margin) * voxel;
  lattice.values.assign(lattice.node_count(), 0.0f);
  lattice.fixed.assign(lattice.node_count(), 0);
  const auto node_of = [&](VoxelKey key) {
    const Eigen::Vector3i c = unpack_key(key) - lo;
    return lattice.index(c.x(), c.y(), c.z());
  };

  // 2. Held nodes: the lattice's faces (outside), seen-empty nodes, then the data's corners.
  const Eigen::Vector3i n = lattice.size;
  tbb::parallel_for(0, n.z(), [&](int z) {
    for (int y = 0; y < n.y(); ++y)
      for (int x = 0; x < n.x(); ++x) {
        if (x > 0 && y > 0 && z > 0 && x + 1 < n.x() && y + 1 < n.y() && z + 1 < n.z()) continue;
        const std::size_t i = lattice.index(x, y, z);
        lattice.fixed[i] = 1;
        lattice.values[i] = outside;
      }
  });
  for (std::size_t c = 0; c < grid.corners.size(); ++c) {
    if (!field.valid[c]) continue;
    const std::size_t i = node_of(grid.corners[c]);
    lattice.fixed[i] = 1;
    lattice.values[i] = field.values[c];
    ++r.observed;
  }
  if (cloud.has_sensor_origin && !cloud.empty()) {  // data wins over a grazing line of sight
    const float stop = config.free_space_stop_voxels * voxel;
    const std::vector<std::uint8_t> empty = seen_empty_nodes(cloud, lo, n, voxel, stop);
    for (std::size_t i = 0; i < empty.size(); ++i) {
      if (!empty[i] || lattice.fixed[i]) continue;
      lattice.fixed[i] = 1;
      lattice.values[i] = stop;
      ++r.seen_empty;
    }
  }

  // 3. Diffusion into the free nodes.
  r.levels = diffuse_free_nodes(lattice, config.diffusion);
  r.filled = lattice.node_count() -
             static_cast<std::size_t>(std::count(lattice.fixed.begin(), lattice.fixed.end(), 1));

  // 4. The grid's cells and those the filled surface crosses, and a value at every corner.
  const std::vector<VoxelKey> added = crossed_cells(lattice, lo, grid.cells);
  r.cells_added = added.size();
  std::vector<VoxelKey> cells;
  cells.reserve(grid.cells.size() + added.size());
  std::merge(grid.cells.begin(), grid.cells.end(), added.begin(), added.end(),
             std::back_inserter(cells));
  out.grid = grid_of_cells(std::move(cells), voxel);
  out.distance.values.resize(out.grid.corners.size());
  out.distance.valid.assign(out.grid.corners.size(), 1);
  tbb::parallel_for(std::size_t{0}, out.grid.corners.size(), [&](std::size_t c) {
    out.distance.values[c] = lattice.values[node_of(out.grid.corners[c])];
  });
  out.distance.disagreeing = field.disagreeing;
  out.distance.extrapolated = field.extrapolated;
  r.ran = true;
  if (report != nullptr) *report = r;
  return out;
}

}  // namespace meshflow
