#include "nodes/optimize/features.h"

#include <algorithm>
#include <cmath>

#include "runtime/angles.h"
#include "runtime/disjoint_sets.h"

namespace meshflow {

bool MeshFeatures::has_edge(std::uint32_t a, std::uint32_t b) const {
  const std::array<std::uint32_t, 2> key{std::min(a, b), std::max(a, b)};
  return std::binary_search(edges.begin(), edges.end(), key);
}

std::size_t MeshFeatures::count(VertexKind kind) const {
  return static_cast<std::size_t>(std::count(vertex_kind.begin(), vertex_kind.end(), kind));
}

MeshFeatures detect_features(const TriangleMesh& mesh, float angle_deg) {
  MeshFeatures f;
  const std::size_t n = mesh.vertices.size();
  f.vertex_kind.assign(n, MeshFeatures::VertexKind::kFree);
  if (!(angle_deg < 180.0f)) return f;
  const float cos_limit = static_cast<float>(std::cos(radians(static_cast<double>(angle_deg))));
  // Every face's edges as (undirected key, face), sorted: an edge's faces are neighbours.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> sides;
  sides.reserve(3 * mesh.triangles.size());
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k)
      sides.emplace_back(undirected_edge_key(mesh.triangles[t][k], mesh.triangles[t][(k + 1) % 3]),
                         t);
  std::sort(sides.begin(), sides.end());
  for (std::size_t i = 0; i < sides.size();) {
    std::size_t j = i;
    while (j < sides.size() && sides[j].first == sides[i].first) ++j;
    if (j - i == 2) {
      const Eigen::Vector3f n0 = face_normal(mesh, mesh.triangles[sides[i].second]);
      const Eigen::Vector3f n1 = face_normal(mesh, mesh.triangles[sides[i + 1].second]);
      if (n0.squaredNorm() > 0.0f && n1.squaredNorm() > 0.0f && n0.dot(n1) < cos_limit)
        f.edges.push_back({static_cast<std::uint32_t>(sides[i].first >> 32),
                           static_cast<std::uint32_t>(sides[i].first & 0xFFFFFFFFu)});
    }
    i = j;
  }
  // Short connected sets of sharp edges are noise (kMinFeatureEdges).
  DisjointSets sets(n);
  for (const auto& e : f.edges) sets.unite(e[0], e[1]);
  std::vector<std::uint32_t> edges_in_set(n, 0);
  for (const auto& e : f.edges) ++edges_in_set[sets.find(e[0])];
  f.edges.erase(std::remove_if(f.edges.begin(), f.edges.end(),
                               [&](const std::array<std::uint32_t, 2>& e) {
                                 return edges_in_set[sets.find(e[0])] < kMinFeatureEdges;
                               }),
                f.edges.end());
  // Vertex kinds from their sharp edges (edges are sorted, so each vertex's first two
  // neighbours are found in one sweep).
  std::vector<std::uint32_t> degree(n, 0);
  std::vector<std::array<std::uint32_t, 2>> ends(n, {0, 0});
  for (const auto& e : f.edges)
    for (int s = 0; s < 2; ++s) {
      const std::uint32_t v = e[s], other = e[1 - s];
      if (degree[v] < 2) ends[v][degree[v]] = other;
      ++degree[v];
    }
  for (std::size_t v = 0; v < n; ++v) {
    if (degree[v] == 0) continue;
    f.vertex_kind[v] = MeshFeatures::VertexKind::kCorner;
    if (degree[v] != 2) continue;
    const Eigen::Vector3f in = (mesh.vertices[v] - mesh.vertices[ends[v][0]]).normalized();
    const Eigen::Vector3f out = (mesh.vertices[ends[v][1]] - mesh.vertices[v]).normalized();
    if (in.dot(out) >= cos_limit) f.vertex_kind[v] = MeshFeatures::VertexKind::kLine;
  }
  return f;
}

}  // namespace meshflow
