#include "nodes/filter/point_clusters.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "runtime/error.h"
#include "runtime/parallel.h"

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

// The components of the radius graph (points at most `radius` apart linked) on a grid of cells
// of edge radius / 1.74 (two points of one cell are closer than 0.996 radius: linked; a cell's
// links reach the cells within 2 along each axis): cells united whole, neighbouring cells when
// some pair of their points is within the radius (the kd-tree's squared distance, inclusive).
// Per point, its component's size (`size`) and the number of components of at least
// `min_points` (`large`); false when the cells do not fit the packed keys.
bool grid_cluster_sizes(const PointCloud& cloud, float radius, std::size_t min_points,
                        std::vector<std::uint32_t>& size, std::size_t& large) {
  const std::size_t n = cloud.size();
  const double edge = static_cast<double>(radius) / 1.74;
  std::vector<std::array<std::int64_t, 3>> cell(n);
  std::array<std::int64_t, 3> lo{}, hi{};
  for (std::size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) {
      const double c = std::floor(static_cast<double>(cloud.positions[i][a]) / edge);
      if (!(std::abs(c) < 1e15)) return false;
      cell[i][a] = static_cast<std::int64_t>(c);
      lo[a] = i == 0 ? cell[i][a] : std::min(lo[a], cell[i][a]);
      hi[a] = i == 0 ? cell[i][a] : std::max(hi[a], cell[i][a]);
    }
  }
  for (int a = 0; a < 3; ++a)
    if (hi[a] - lo[a] > kCellSpan) return false;
  // Packed keys, coordinates shifted by 2 so that every neighbour's key is a key too.
  const auto pack = [&](const std::array<std::int64_t, 3>& c) {
    std::uint64_t key = 0;
    for (int a = 0; a < 3; ++a)
      key = key << kCellBits | static_cast<std::uint64_t>(c[a] - lo[a] + 2);
    return key;
  };
  std::vector<std::pair<std::uint64_t, std::uint32_t>> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = {pack(cell[i]), static_cast<std::uint32_t>(i)};
  cell = {};
  std::sort(order.begin(), order.end());
  // Cells: runs of one key; an open-addressing table from key to cell.
  std::vector<std::uint32_t> first;  // per cell, its first position in `order`, and n at the end
  for (std::size_t i = 0; i < n; ++i)
    if (i == 0 || order[i].first != order[i - 1].first)
      first.push_back(static_cast<std::uint32_t>(i));
  const std::size_t cells = first.size();
  first.push_back(static_cast<std::uint32_t>(n));
  std::size_t capacity = 16;
  int bits = 4;
  for (; capacity < 2 * cells; capacity *= 2) ++bits;
  constexpr std::uint32_t kEmpty = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> table(capacity, kEmpty);
  const auto slot = [&](std::uint64_t key) {  // the product's top bits: every axis counts
    return static_cast<std::size_t>((key * 0x9e3779b97f4a7c15ULL) >> (64 - bits));
  };
  for (std::uint32_t c = 0; c < cells; ++c) {
    std::size_t s = slot(order[first[c]].first);
    while (table[s] != kEmpty) s = (s + 1) & (capacity - 1);
    table[s] = c;
  }
  const auto find_cell = [&](std::uint64_t key) {
    for (std::size_t s = slot(key);; s = (s + 1) & (capacity - 1)) {
      if (table[s] == kEmpty) return kEmpty;
      if (order[first[table[s]]].first == key) return table[s];
    }
  };
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
  std::vector<std::uint32_t> parent(cells);
  std::iota(parent.begin(), parent.end(), 0u);
  const float r2 = radius * radius;
  for (const std::vector<std::int64_t>& offsets : forward)
    for (std::uint32_t c = 0; c < cells; ++c) {
      const std::uint64_t key = order[first[c]].first;
      for (const std::int64_t offset : offsets) {
        const std::uint32_t d = find_cell(key + static_cast<std::uint64_t>(offset));
        if (d == kEmpty) continue;
        std::uint32_t a = cluster_root(parent, c), b = cluster_root(parent, d);
        if (a == b) continue;
        bool linked = false;
        for (std::uint32_t i = first[c]; i < first[c + 1] && !linked; ++i)
          for (std::uint32_t j = first[d]; j < first[d + 1] && !linked; ++j)
            linked = cluster_distance2(cloud.positions[order[j].second],
                                       cloud.positions[order[i].second]) <= r2;
        if (!linked) continue;
        if (a > b) std::swap(a, b);
        parent[b] = a;
      }
    }
  std::vector<std::uint32_t> points(cells, 0);
  for (std::uint32_t c = 0; c < cells; ++c) {
    parent[c] = cluster_root(parent, c);  // every cell points at its root from here on
    points[parent[c]] += first[c + 1] - first[c];
  }
  large = 0;
  for (std::uint32_t c = 0; c < cells; ++c)
    if (parent[c] == c && points[c] >= min_points) ++large;
  size.assign(n, 0);
  for (std::uint32_t c = 0; c < cells; ++c)
    for (std::uint32_t i = first[c]; i < first[c + 1]; ++i)
      size[order[i].second] = points[parent[c]];
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
  std::vector<std::uint32_t> size;
  if (!grid_cluster_sizes(cloud, config.link_radius, config.min_points, size, c.clusters))
    return knn_cluster_indices(cloud, index, config, counts);
  for (std::size_t i = 0; i < n; ++i) {
    if (size[i] == 1)
      ++c.isolated;
    else if (size[i] < config.min_points)
      ++c.sparse;
  }
  if (counts != nullptr) *counts = c;
  return parallel_select_indices(n, [&](std::size_t i) { return size[i] >= config.min_points; });
}

}  // namespace meshflow
