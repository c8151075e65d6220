#include "nodes/filter/point_clusters.h"

#include <tbb/parallel_for.h>

#include <algorithm>
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

}  // namespace meshflow
