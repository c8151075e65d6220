#include "runtime/triangle_mesh.h"

#include <tbb/parallel_sort.h>

#include <algorithm>

namespace meshflow {

Eigen::Vector3f face_normal(const TriangleMesh& mesh, const Triangle& t) {
  const Eigen::Vector3f& a = mesh.vertices[t[0]];
  const Eigen::Vector3f n = (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a);
  const float len = n.norm();
  return len > 0.0f ? Eigen::Vector3f(n / len) : Eigen::Vector3f::Zero();
}

EdgeStatistics edge_statistics(const TriangleMesh& mesh) {
  // Key: (min vertex, max vertex) with the direction in the lowest bit.
  std::vector<std::uint64_t> keys;
  keys.reserve(mesh.triangles.size() * 3);
  for (const Triangle& t : mesh.triangles) {
    for (int i = 0; i < 3; ++i) {
      const std::uint64_t a = t[i], b = t[(i + 1) % 3];
      const std::uint64_t lo = std::min(a, b), hi = std::max(a, b);
      keys.push_back(((lo << 32 | hi) << 1) | (a < b ? 0u : 1u));
    }
  }
  tbb::parallel_sort(keys.begin(), keys.end());
  EdgeStatistics stats;
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i;
    std::size_t forward = 0;
    while (j < keys.size() && (keys[j] >> 1) == (keys[i] >> 1)) {
      forward += (keys[j] & 1u) == 0 ? 1 : 0;
      ++j;
    }
    const std::size_t count = j - i;
    ++stats.edges;
    if (count == 1) ++stats.boundary_edges;
    if (count > 2) ++stats.non_manifold_edges;
    if (count == 2 && forward != 1) ++stats.inconsistent_edges;
    i = j;
  }
  return stats;
}

std::vector<BorderEdge> border_edges(const TriangleMesh& mesh) {
  struct Directed {
    std::uint64_t key;  // min vertex << 32 | max vertex
    BorderEdge edge;
  };
  std::vector<Directed> edges;
  edges.reserve(mesh.triangles.size() * 3);
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t a = mesh.triangles[t][i], b = mesh.triangles[t][(i + 1) % 3];
      const std::uint64_t key = std::uint64_t{std::min(a, b)} << 32 | std::max(a, b);
      edges.push_back({key, {a, b, t}});
    }
  }
  // A total order (a triangle has an edge once): the parallel sort is deterministic.
  tbb::parallel_sort(edges.begin(), edges.end(), [](const Directed& x, const Directed& y) {
    return x.key != y.key ? x.key < y.key : x.edge.triangle < y.edge.triangle;
  });
  std::vector<BorderEdge> border;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j].key == edges[i].key) ++j;
    if (j - i == 1) border.push_back(edges[i].edge);
    i = j;
  }
  return border;
}

}  // namespace meshflow
