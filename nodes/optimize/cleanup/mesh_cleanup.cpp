#include "nodes/optimize/cleanup/mesh_cleanup.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

#include "nodes/optimize/cleanup/manifold_repair.h"
#include "runtime/error.h"

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
// their lowest vertex, so faces are grouped by it (a counting sort, which keeps each group in
// index order) and only the few faces of a group are compared, pairwise. O(V + T) plus O(g^2)
// per group of g faces.
std::vector<std::uint8_t> duplicate_faces(const std::vector<Triangle>& tris,
                                          std::size_t vertex_count) {
  std::vector<std::uint32_t> start(vertex_count + 1, 0);
  const auto lowest = [&](const Triangle& t) { return std::min({t[0], t[1], t[2]}); };
  for (const Triangle& t : tris)
    if (lowest(t) < vertex_count) ++start[lowest(t) + 1];
  for (std::size_t v = 0; v < vertex_count; ++v) start[v + 1] += start[v];
  std::vector<std::uint32_t> grouped(start.back());
  {
    std::vector<std::uint32_t> next(start.begin(), start.end() - 1);
    for (std::uint32_t i = 0; i < tris.size(); ++i)
      if (lowest(tris[i]) < vertex_count) grouped[next[lowest(tris[i])]++] = i;
  }
  std::vector<std::uint8_t> dup(tris.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertex_count, 4096),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t v = range.begin(); v != range.end(); ++v)
                        for (std::uint32_t j = start[v] + 1; j < start[v + 1]; ++j) {
                          const Triangle tj = sorted_corners(tris[grouped[j]]);
                          for (std::uint32_t i = start[v]; i < j; ++i)
                            if (sorted_corners(tris[grouped[i]]) == tj) {
                              dup[grouped[j]] = 1;
                              break;
                            }
                        }
                    });
  return dup;
}

}  // namespace

namespace {

// remove_small_components() (runtime/triangle_mesh.h), counted into the report.
void remove_small_components(std::vector<Triangle>& triangles, std::size_t vertex_count,
                             std::size_t min_triangles, CleanupReport& r,
                             const std::vector<std::uint8_t>* held = nullptr) {
  ComponentCounts counts;
  meshflow::remove_small_components(triangles, vertex_count, min_triangles, &counts, held);
  r.components += counts.components;
  r.removed_components += counts.removed_components;
  r.removed_component_triangles += counts.removed_triangles;
}

}  // namespace

TriangleMesh clean_mesh(const TriangleMesh& mesh, const CleanupConfig& config,
                        CleanupReport* report, const std::vector<std::uint8_t>* held,
                        std::vector<std::uint32_t>* kept_vertices) {
  if (held != nullptr && config.non_manifold_vertices == NonManifoldVertexRepair::kSplit)
    throw Error("clean", "held",
                "seam vertices cannot be held fixed while non-manifold vertices are split");
  CleanupReport r;
  std::vector<Triangle> kept;
  kept.reserve(mesh.triangles.size());
  if (config.remove_degenerate) {
    std::vector<std::uint8_t> degenerate(mesh.triangles.size());
    tbb::parallel_for(std::size_t{0}, mesh.triangles.size(), [&](std::size_t i) {
      degenerate[i] = is_degenerate(mesh, mesh.triangles[i]) ? 1 : 0;
    });
    const std::vector<std::uint8_t> dup = duplicate_faces(mesh.triangles, mesh.vertices.size());
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
      if (degenerate[i]) {
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

  if (config.non_manifold_vertices == NonManifoldVertexRepair::kRemoveSmallerFans) {
    FanRemovalCounts fans;
    remove_smaller_fans(kept, mesh.vertices.size(), &fans, held);
    r.non_manifold_vertices = fans.vertices;
    r.removed_fan_triangles = fans.triangles;
  }
  // After the fans: a piece that hung on the rest by a vertex is a component of its own now.
  remove_small_components(kept, mesh.vertices.size(), config.min_component_triangles, r, held);
  TriangleMesh out = compact_vertices(mesh, kept, kept_vertices);
  r.removed_vertices = mesh.vertices.size() - out.vertices.size();
  if (config.non_manifold_vertices == NonManifoldVertexRepair::kSplit) {
    r.split_vertices = split_non_manifold_vertices(out);
    // Splitting separates the fans that met at a vertex: pieces that hung on the rest of the
    // mesh by one vertex become components of their own and get the same size rule.
    if (r.split_vertices > 0 && config.min_component_triangles > 0) {
      CleanupReport after_split;
      std::vector<Triangle> split = out.triangles;
      remove_small_components(split, out.vertices.size(), config.min_component_triangles,
                              after_split);
      if (after_split.removed_components > 0) {
        r.removed_components += after_split.removed_components;
        r.removed_component_triangles += after_split.removed_component_triangles;
        const std::size_t before = out.vertices.size();
        out = compact_vertices(out, split);
        r.removed_vertices += before - out.vertices.size();
      }
    }
  }
  if (report != nullptr) *report = r;
  return out;
}

}  // namespace meshflow
