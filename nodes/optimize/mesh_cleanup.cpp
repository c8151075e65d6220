#include "nodes/optimize/mesh_cleanup.h"

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <numeric>

namespace meshflow {
namespace {

bool is_degenerate(const TriangleMesh& mesh, const Triangle& t) {
  if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return true;
  const Eigen::Vector3f& a = mesh.vertices[t[0]];
  return (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a).squaredNorm() == 0.0f;
}

// Marks the second and later copies of a face with the same vertex set.
std::vector<bool> duplicate_faces(const std::vector<Triangle>& tris) {
  std::vector<std::pair<Triangle, std::uint32_t>> sorted(tris.size());
  for (std::size_t i = 0; i < tris.size(); ++i) {
    Triangle t = tris[i];
    std::sort(t.begin(), t.end());
    sorted[i] = {t, static_cast<std::uint32_t>(i)};
  }
  tbb::parallel_sort(sorted.begin(), sorted.end());
  std::vector<bool> dup(tris.size(), false);
  for (std::size_t i = 1; i < sorted.size(); ++i) {
    if (sorted[i].first == sorted[i - 1].first) dup[sorted[i].second] = true;
  }
  return dup;
}

struct DisjointSets {
  std::vector<std::uint32_t> parent;
  explicit DisjointSets(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  std::uint32_t find(std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

}  // namespace

TriangleMesh clean_mesh(const TriangleMesh& mesh, const CleanupConfig& config,
                        CleanupReport* report) {
  CleanupReport r;
  std::vector<Triangle> kept;
  kept.reserve(mesh.triangles.size());
  if (config.remove_degenerate) {
    const std::vector<bool> dup = duplicate_faces(mesh.triangles);
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
      if (is_degenerate(mesh, mesh.triangles[i])) {
        ++r.degenerate_triangles;
      } else if (dup[i]) {
        ++r.duplicate_triangles;
      } else {
        kept.push_back(mesh.triangles[i]);
      }
    }
  } else {
    kept = mesh.triangles;
  }

  // Components by shared vertices; drop the small ones.
  DisjointSets sets(mesh.vertices.size());
  for (const Triangle& t : kept) {
    sets.unite(t[0], t[1]);
    sets.unite(t[1], t[2]);
  }
  std::vector<std::uint32_t> component_size(mesh.vertices.size(), 0);
  for (const Triangle& t : kept) ++component_size[sets.find(t[0])];
  for (std::uint32_t s : component_size) {
    if (s == 0) continue;
    ++r.components;
    if (s < config.min_component_triangles) {
      ++r.removed_components;
      r.removed_component_triangles += s;
    }
  }
  if (config.min_component_triangles > 0) {
    kept.erase(std::remove_if(kept.begin(), kept.end(),
                              [&](const Triangle& t) {
                                return component_size[sets.find(t[0])] <
                                       config.min_component_triangles;
                              }),
               kept.end());
  }

  // Compact vertices, keeping their order.
  std::vector<std::uint32_t> remap(mesh.vertices.size(), UINT32_MAX);
  for (const Triangle& t : kept) {
    for (std::uint32_t v : t) remap[v] = 0;
  }
  TriangleMesh out;
  const bool normals = mesh.normals.size() == mesh.vertices.size();
  const bool colors = mesh.colors.size() == mesh.vertices.size();
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    if (remap[v] == UINT32_MAX) continue;
    remap[v] = static_cast<std::uint32_t>(out.vertices.size());
    out.vertices.push_back(mesh.vertices[v]);
    if (normals) out.normals.push_back(mesh.normals[v]);
    if (colors) out.colors.push_back(mesh.colors[v]);
  }
  r.removed_vertices = mesh.vertices.size() - out.vertices.size();
  out.triangles.resize(kept.size());
  for (std::size_t i = 0; i < kept.size(); ++i) {
    out.triangles[i] = Triangle{remap[kept[i][0]], remap[kept[i][1]], remap[kept[i][2]]};
  }
  if (report != nullptr) *report = r;
  return out;
}

}  // namespace meshflow
