#include "nodes/filter/point_clusters.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <string>
#include <utility>

#include "runtime/concurrent_disjoint_sets.h"
#include "runtime/default_init.h"
#include "runtime/error.h"
#include "runtime/parallel.h"
#include "runtime/radix_sort.h"

namespace meshflow {
namespace {

// Root of i's set with path halving; parents always point to smaller indices.
std::uint32_t cluster_root(std::vector<std::uint32_t>& parent, std::uint32_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

// The kNN-then-radius linking (exact: the clusters reaching min_points are those of the radius
// graph), for clouds too wide for grid_cluster_sizes()'s packed cells.
std::vector<std::uint32_t> knn_cluster_indices(const PointCloud& cloud, const SpatialIndex& index,
                                               const ClusterConfig& config, ClusterCounts* counts) {
  const std::size_t n = cloud.size();
  ClusterCounts c;
  const std::size_t k = static_cast<std::size_t>(std::clamp(config.k, 1, 64));
  const std::size_t kq = k + 1;  // the point itself comes first
  const float r2 = config.link_radius * config.link_radius;
  // links[i * k + j]: i's j-th neighbour within the radius, or i itself (no link).
  std::vector<std::uint32_t> links(n * k);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      std::uint32_t idx[65];
                      float d2[65];
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        const std::size_t found = index.knn(cloud.positions[i], kq, idx, d2);
                        std::uint32_t* out = links.data() + i * k;
                        std::size_t used = 0;
                        for (std::size_t j = 0; j < found && used < k; ++j)
                          if (idx[j] != i && d2[j] <= r2) out[used++] = idx[j];
                        for (; used < k; ++used) out[used] = static_cast<std::uint32_t>(i);
                      }
                    });
  std::vector<std::uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < k; ++j) {
      std::uint32_t a = cluster_root(parent, static_cast<std::uint32_t>(i));
      std::uint32_t b = cluster_root(parent, links[i * k + j]);
      if (a == b) continue;
      if (a > b) std::swap(a, b);
      parent[b] = a;
    }
  }
  std::vector<std::uint32_t> size(n, 0);
  const auto count_sizes = [&] {
    std::fill(size.begin(), size.end(), 0u);
    for (std::size_t i = 0; i < n; ++i) {
      parent[i] = cluster_root(parent, static_cast<std::uint32_t>(i));
      ++size[parent[i]];
    }
  };
  count_sizes();
  // The k links can split an anisotropic sampling (a scan line at a grazing angle links only
  // along itself): the points of clusters still too small link to every point within the
  // radius. Every link of the radius graph with an end in a small cluster is then present, so
  // the clusters that reach min_points are exactly those of the radius graph.
  const std::vector<std::uint32_t> small = parallel_select_indices(
      n, [&](std::size_t i) { return size[parent[i]] < config.min_points; });
  std::vector<std::vector<std::uint32_t>> near(small.size());
  tbb::parallel_for(std::size_t{0}, small.size(), [&](std::size_t s) {
    near[s] = index.radius_search(cloud.positions[small[s]], config.link_radius);
  });
  for (std::size_t s = 0; s < small.size(); ++s) {
    for (std::uint32_t j : near[s]) {
      std::uint32_t a = cluster_root(parent, small[s]);
      std::uint32_t b = cluster_root(parent, j);
      if (a == b) continue;
      if (a > b) std::swap(a, b);
      parent[b] = a;
    }
  }
  count_sizes();
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t s = size[parent[i]];
    if (s == 1)
      ++c.isolated;
    else if (s < config.min_points)
      ++c.sparse;
    else if (parent[i] == i)
      ++c.clusters;
  }
  if (counts != nullptr) *counts = c;
  return parallel_select_indices(
      n, [&](std::size_t i) { return size[parent[i]] >= config.min_points; });
}

// Squared distance of a and b as the kd-tree computes it: ((dx dx + dy dy) + dz dz).
float cluster_distance2(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  const float dx = a.x() - b.x(), dy = a.y() - b.y(), dz = a.z() - b.z();
  return (dx * dx + dy * dy) + dz * dz;
}

constexpr int kCellBits = 21;  // per axis in a packed cell key
constexpr std::int64_t kCellSpan = (std::int64_t{1} << kCellBits) - 5;
constexpr std::size_t kPointGrain = 8192;  // points per parallel block
constexpr std::size_t kCellGrain = 256;    // cells per parallel block

// A point's grid cell: floor(coordinate / edge) per axis.
struct CellCoords {
  std::int64_t c[3] = {0, 0, 0};
};

// The range of the points' cells, and whether every point has one (finite, |cell| < 1e15).
struct CellRange {
  std::int64_t lo[3] = {std::numeric_limits<std::int64_t>::max(),
                        std::numeric_limits<std::int64_t>::max(),
                        std::numeric_limits<std::int64_t>::max()};
  std::int64_t hi[3] = {std::numeric_limits<std::int64_t>::min(),
                        std::numeric_limits<std::int64_t>::min(),
                        std::numeric_limits<std::int64_t>::min()};
  bool valid = true;
  void join(const CellRange& o) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], o.lo[a]);
      hi[a] = std::max(hi[a], o.hi[a]);
    }
    valid = valid && o.valid;
  }
};

// The cell of point p; false when a coordinate is not finite or too far from the origin.
bool cell_of(const Eigen::Vector3f& p, double edge, CellCoords& cell) {
  for (int a = 0; a < 3; ++a) {
    const double c = std::floor(static_cast<double>(p[a]) / edge);
    if (!(std::abs(c) < 1e15)) return false;
    cell.c[a] = static_cast<std::int64_t>(c);
  }
  return true;
}

// min / max over the points' cells, in parallel (the same for any split).
CellRange cell_range(const PointCloud& cloud, double edge) {
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, cloud.size(), kPointGrain), CellRange{},
      [&](const tbb::blocked_range<std::size_t>& r, CellRange range) {
        CellCoords cell;
        for (std::size_t i = r.begin(); i != r.end() && range.valid; ++i) {
          if (!cell_of(cloud.positions[i], edge, cell)) {
            range.valid = false;
            break;
          }
          for (int a = 0; a < 3; ++a) {
            range.lo[a] = std::min(range.lo[a], cell.c[a]);
            range.hi[a] = std::max(range.hi[a], cell.c[a]);
          }
        }
        return range;
      },
      [](CellRange a, const CellRange& b) {
        a.join(b);
        return a;
      });
}

int bit_width(std::uint64_t v) {
  int bits = 0;
  for (; v != 0; v >>= 1) ++bits;
  return bits;
}

// A point in cell order: its cell's packed key (coordinates - lo + 2, kCellBits per axis, so
// that every neighbour within 2 has a key too) and its index.
struct CellPoint {
  std::uint64_t key;
  std::uint32_t id;
};

// The points ordered by (packed cell key, index). One radix sort of (cell offsets, index) keys
// where those fit in 64 bits (at most 21 bits per axis plus the index's); else a parallel
// comparison sort of the pairs (unique, so the order is the same).
UninitVector<CellPoint> points_by_cell(const PointCloud& cloud, double edge,
                                       const CellRange& range) {
  const std::size_t n = cloud.size();
  int bits[3];
  for (int a = 0; a < 3; ++a)
    bits[a] = bit_width(static_cast<std::uint64_t>(range.hi[a] - range.lo[a]));
  const int index_bits = bit_width(n - 1);
  const auto offsets = [&](std::size_t i) {
    CellCoords cell;
    cell_of(cloud.positions[i], edge, cell);  // valid: checked by cell_range()
    std::uint64_t d[3];
    for (int a = 0; a < 3; ++a) d[a] = static_cast<std::uint64_t>(cell.c[a] - range.lo[a]);
    return std::array<std::uint64_t, 3>{d[0], d[1], d[2]};
  };
  const auto pack = [](const std::array<std::uint64_t, 3>& d) {
    return ((d[0] + 2) << kCellBits | (d[1] + 2)) << kCellBits | (d[2] + 2);
  };
  UninitVector<CellPoint> order(n);
  if (bits[0] + bits[1] + bits[2] + index_bits <= 64) {
    std::vector<std::uint64_t> keys(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kPointGrain),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t i = r.begin(); i != r.end(); ++i) {
                          const std::array<std::uint64_t, 3> d = offsets(i);
                          keys[i] = ((d[0] << bits[1] | d[1]) << bits[2] | d[2]) << index_bits | i;
                        }
                      });
    radix_sort(keys);
    const std::uint64_t index_mask = (std::uint64_t{1} << index_bits) - 1;
    const std::uint64_t mask1 = (std::uint64_t{1} << bits[1]) - 1;
    const std::uint64_t mask2 = (std::uint64_t{1} << bits[2]) - 1;
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, n, kPointGrain),
        [&](const tbb::blocked_range<std::size_t>& r) {
          for (std::size_t p = r.begin(); p != r.end(); ++p) {
            const std::uint64_t cell = keys[p] >> index_bits;
            order[p] = {pack({cell >> bits[2] >> bits[1], (cell >> bits[2]) & mask1, cell & mask2}),
                        static_cast<std::uint32_t>(keys[p] & index_mask)};
          }
        });
  } else {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kPointGrain),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t i = r.begin(); i != r.end(); ++i)
                          order[i] = {pack(offsets(i)), static_cast<std::uint32_t>(i)};
                      });
    tbb::parallel_sort(order.begin(), order.end(), [](const CellPoint& a, const CellPoint& b) {
      return a.key != b.key ? a.key < b.key : a.id < b.id;
    });
  }
  return order;
}

// Cells' packed keys to cell numbers: open addressing, filled in parallel (the slots a key
// lands in depend on the schedule, the cell a lookup finds does not).
class CellTable {
 public:
  static constexpr std::uint32_t kEmpty = std::numeric_limits<std::uint32_t>::max();

  CellTable(const UninitVector<CellPoint>& order, const std::vector<std::uint32_t>& first)
      : order_(order), first_(first) {
    const std::size_t cells = first.size() - 1;
    std::size_t capacity = 16;
    for (bits_ = 4; capacity < 2 * cells; capacity *= 2) ++bits_;
    mask_ = capacity - 1;
    slots_ = std::vector<std::atomic<std::uint32_t>>(capacity);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, capacity, kPointGrain),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t s = r.begin(); s != r.end(); ++s)
                          slots_[s].store(kEmpty, std::memory_order_relaxed);
                      });
    tbb::parallel_for(
        tbb::blocked_range<std::uint32_t>(0, static_cast<std::uint32_t>(cells), kPointGrain),
        [&](const tbb::blocked_range<std::uint32_t>& r) {
          for (std::uint32_t c = r.begin(); c != r.end(); ++c) {
            for (std::size_t s = slot(key(c));; s = (s + 1) & mask_) {
              std::uint32_t expected = kEmpty;
              if (slots_[s].compare_exchange_strong(expected, c, std::memory_order_relaxed)) break;
            }
          }
        });
  }
  // Cell c's packed key.
  std::uint64_t key(std::uint32_t c) const { return order_[first_[c]].key; }
  // The cell of packed key `k`, or kEmpty. Thread-safe once built.
  std::uint32_t find(std::uint64_t k) const {
    for (std::size_t s = slot(k);; s = (s + 1) & mask_) {
      const std::uint32_t c = slots_[s].load(std::memory_order_relaxed);
      if (c == kEmpty || key(c) == k) return c;
    }
  }

 private:
  std::size_t slot(std::uint64_t k) const {  // the product's top bits: every axis counts
    return static_cast<std::size_t>((k * 0x9e3779b97f4a7c15ULL) >> (64 - bits_));
  }
  const UninitVector<CellPoint>& order_;
  const std::vector<std::uint32_t>& first_;
  int bits_ = 4;
  std::size_t mask_ = 15;
  std::vector<std::atomic<std::uint32_t>> slots_;
};

// The components of the radius graph (points at most `radius` apart linked) on a grid of cells
// of edge radius / 1.74 (two points of one cell are closer than 0.996 radius: linked; a cell's
// links reach the cells within 2 along each axis): cells united whole, neighbouring cells when
// some pair of their points is within the radius (the kd-tree's squared distance, inclusive).
// Per point, its component's size (`size`) and the number of components of at least
// `min_points` (`large`); false when the cells do not fit the packed keys. Every pass is
// parallel (a concurrent union-find: components do not depend on the order of the unions).
bool grid_cluster_sizes(const PointCloud& cloud, float radius, std::size_t min_points,
                        UninitVector<std::uint32_t>& size, std::size_t& large) {
  const std::size_t n = cloud.size();
  const double edge = static_cast<double>(radius) / 1.74;
  const CellRange range = cell_range(cloud, edge);
  if (!range.valid) return false;
  for (int a = 0; a < 3; ++a)
    if (range.hi[a] - range.lo[a] > kCellSpan) return false;
  const UninitVector<CellPoint> order = points_by_cell(cloud, edge, range);
  // Cells: runs of one key. Per cell, its first position in `order`, and n at the end.
  std::vector<std::uint32_t> first = parallel_select_indices(
      n, [&](std::size_t p) { return p == 0 || order[p].key != order[p - 1].key; });
  const auto cells = static_cast<std::uint32_t>(first.size());
  first.push_back(static_cast<std::uint32_t>(n));
  const CellTable table(order, first);
  // The 62 neighbours after a cell in key order (offsets within 2 along each axis): the 13
  // adjacent ones first, over every cell, so that the others, whose points are mostly beyond
  // the radius, are mostly in one component already and cost a lookup (components do not
  // depend on the order of the unions).
  std::vector<std::int64_t> forward[2];
  for (std::int64_t dx = -2; dx <= 2; ++dx)
    for (std::int64_t dy = -2; dy <= 2; ++dy)
      for (std::int64_t dz = -2; dz <= 2; ++dz) {
        const std::int64_t offset =
            (dx * (std::int64_t{1} << kCellBits) + dy) * (std::int64_t{1} << kCellBits) + dz;
        const bool adjacent = std::abs(dx) <= 1 && std::abs(dy) <= 1 && std::abs(dz) <= 1;
        if (offset > 0) forward[adjacent ? 0 : 1].push_back(offset);
      }
  ConcurrentParents parent = concurrent_singletons(cells);
  const float r2 = radius * radius;
  for (const std::vector<std::int64_t>& offsets : forward) {
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, cells, kCellGrain),
                      [&](const tbb::blocked_range<std::uint32_t>& r) {
                        for (std::uint32_t c = r.begin(); c != r.end(); ++c) {
                          const std::uint64_t key = table.key(c);
                          for (const std::int64_t offset : offsets) {
                            const std::uint32_t d =
                                table.find(key + static_cast<std::uint64_t>(offset));
                            if (d == CellTable::kEmpty) continue;
                            if (concurrent_find(parent, c) == concurrent_find(parent, d)) continue;
                            bool linked = false;
                            for (std::uint32_t i = first[c]; i < first[c + 1] && !linked; ++i)
                              for (std::uint32_t j = first[d]; j < first[d + 1] && !linked; ++j)
                                linked = cluster_distance2(cloud.positions[order[j].id],
                                                           cloud.positions[order[i].id]) <= r2;
                            if (linked) concurrent_unite(parent, c, d);
                          }
                        }
                      });
  }
  // Per cell its root; per root its component's points.
  UninitVector<std::uint32_t> root(cells);
  std::vector<std::atomic<std::uint32_t>> points(cells);
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, cells, kPointGrain),
                    [&](const tbb::blocked_range<std::uint32_t>& r) {
                      for (std::uint32_t c = r.begin(); c != r.end(); ++c) {
                        root[c] = concurrent_find(parent, c);
                        points[root[c]].fetch_add(first[c + 1] - first[c],
                                                  std::memory_order_relaxed);
                      }
                    });
  large = tbb::parallel_reduce(
      tbb::blocked_range<std::uint32_t>(0, cells, kPointGrain), std::size_t{0},
      [&](const tbb::blocked_range<std::uint32_t>& r, std::size_t count) {
        for (std::uint32_t c = r.begin(); c != r.end(); ++c)
          count += root[c] == c && points[c].load(std::memory_order_relaxed) >= min_points;
        return count;
      },
      std::plus<>());
  size.resize(n);  // every point written below: each lies in one cell
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, cells, kCellGrain),
                    [&](const tbb::blocked_range<std::uint32_t>& r) {
                      for (std::uint32_t c = r.begin(); c != r.end(); ++c) {
                        const std::uint32_t s = points[root[c]].load(std::memory_order_relaxed);
                        for (std::uint32_t p = first[c]; p < first[c + 1]; ++p)
                          size[order[p].id] = s;
                      }
                    });
  return true;
}

}  // namespace

std::vector<std::uint32_t> surface_cluster_indices(const PointCloud& cloud,
                                                   const SpatialIndex& index,
                                                   const ClusterConfig& config,
                                                   ClusterCounts* counts) {
  const std::size_t n = cloud.size();
  ClusterCounts c;
  if (config.min_points <= 1 || n == 0) {
    if (counts != nullptr) *counts = c;
    return parallel_select_indices(n, [](std::size_t) { return true; });
  }
  if (!(config.link_radius > 0.0f))
    throw Error("outliers", "link_radius",
                "must be a positive number of metres, got " + std::to_string(config.link_radius));
  UninitVector<std::uint32_t> size;
  if (!grid_cluster_sizes(cloud, config.link_radius, config.min_points, size, c.clusters))
    return knn_cluster_indices(cloud, index, config, counts);
  // Isolated and sparse points, counted in parallel (integer sums: the same for any split).
  using Pair = std::pair<std::size_t, std::size_t>;
  const Pair dropped = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n, kPointGrain), Pair{0, 0},
      [&](const tbb::blocked_range<std::size_t>& r, Pair sum) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          sum.first += size[i] == 1;
          sum.second += size[i] > 1 && size[i] < config.min_points;
        }
        return sum;
      },
      [](const Pair& a, const Pair& b) {
        return Pair{a.first + b.first, a.second + b.second};
      });
  c.isolated = dropped.first;
  c.sparse = dropped.second;
  if (counts != nullptr) *counts = c;
  return parallel_select_indices(n, [&](std::size_t i) { return size[i] >= config.min_points; });
}

}  // namespace meshflow
