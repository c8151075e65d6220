#include "nodes/optimize/mesh_cleanup.h"

#include <tbb/parallel_for.h>

#include <algorithm>

#include "nodes/optimize/manifold_repair.h"
#include "runtime/disjoint_sets.h"
#include "runtime/radix_sort.h"

namespace meshflow {
namespace {

// Repeated corners, zero area, or a corner at a NaN / infinite position (no defined area: the
// comparison is written so that a NaN area counts as none).
bool is_degenerate(const TriangleMesh& mesh, const Triangle& t) {
  if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return true;
  const Eigen::Vector3f &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]],
                        &c = mesh.vertices[t[2]];
  if (!a.allFinite() || !b.allFinite() || !c.allFinite()) return true;
  return !((b - a).cross(c - a).squaredNorm() > 0.0f);
}

Triangle sorted_corners(Triangle t) {
  std::sort(t.begin(), t.end());
  return t;
}

// Marks the second and later copies (by index) of a face with the same vertex set. Copies share
// their lowest vertex, so faces are grouped by it with a radix sort of (lowest vertex, index)
// and only the few faces of a group are compared. O(n) plus O(g log g) per group of g faces.
std::vector<bool> duplicate_faces(const std::vector<Triangle>& tris) {
  std::vector<std::uint64_t> by_lowest(tris.size());
  tbb::parallel_for(std::size_t{0}, tris.size(), [&](std::size_t i) {
    const Triangle& t = tris[i];
    by_lowest[i] = (std::uint64_t{std::min({t[0], t[1], t[2]})} << 32) | i;
  });
  radix_sort(by_lowest);
  std::vector<bool> dup(tris.size(), false);
  std::vector<std::pair<Triangle, std::uint32_t>> group;
  for (std::size_t begin = 0; begin < by_lowest.size();) {
    std::size_t end = begin + 1;
    while (end < by_lowest.size() && (by_lowest[end] >> 32) == (by_lowest[begin] >> 32)) ++end;
    if (end - begin > 1) {
      group.clear();
      for (std::size_t i = begin; i < end; ++i) {
        const auto index = static_cast<std::uint32_t>(by_lowest[i] & 0xffffffffu);
        group.emplace_back(sorted_corners(tris[index]), index);
      }
      std::sort(group.begin(), group.end());  // equal faces together, lowest index first
      for (std::size_t i = 1; i < group.size(); ++i) {
        if (group[i].first == group[i - 1].first) dup[group[i].second] = true;
      }
    }
    begin = end;
  }
  return dup;
}

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

  TriangleMesh out = compact_vertices(mesh, kept);
  r.removed_vertices = mesh.vertices.size() - out.vertices.size();
  if (config.split_non_manifold_vertices) r.split_vertices = split_non_manifold_vertices(out);
  if (report != nullptr) *report = r;
  return out;
}

}  // namespace meshflow
