#include "runtime/triangle_mesh.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>

#include "runtime/error.h"
#include "runtime/mesh_components.h"
#include "runtime/parallel.h"
#include "runtime/vertex_triangles.h"

namespace meshflow {

Eigen::Vector3f face_normal(const TriangleMesh& mesh, const Triangle& t) {
  const Eigen::Vector3f& a = mesh.vertices[t[0]];
  const Eigen::Vector3f n = (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a);
  const float len = n.norm();
  return len > 0.0f ? Eigen::Vector3f(n / len) : Eigen::Vector3f::Zero();
}

bool has_area(const Eigen::Vector3f& a, const Eigen::Vector3f& b, const Eigen::Vector3f& c) {
  const Eigen::Vector3f ab = b - a, bc = c - b, ca = a - c;
  const float at_a = ab.cross(-ca).squaredNorm(), at_b = bc.cross(-ab).squaredNorm(),
              at_c = ca.cross(-bc).squaredNorm();
  const float longest = std::max({ab.squaredNorm(), bc.squaredNorm(), ca.squaredNorm()});
  constexpr float kFlattest = 1e-6f;
  return at_a > 0.0f && at_b > 0.0f && at_c > 0.0f &&
         at_a >= kFlattest * kFlattest * longest * longest;
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
  return border_edges(mesh, vertex_triangles(mesh));
}

std::vector<BorderEdge> border_edges(const TriangleMesh& mesh, const VertexTriangles& around) {
  const auto& tris = mesh.triangles;
  const auto vertex_count = static_cast<std::uint32_t>(around.offsets.size() - 1);
  // Edge i of triangle t (t[i] -> t[i + 1]) is a border edge when no other triangle around
  // t[i] also has t[i + 1] as a corner. Decided per vertex a for the edges leaving it: a's
  // triangles count, per corner x, how many of them hold x (a per-thread array stamped with a,
  // so nothing is cleared between vertices); only a's task writes the flags of the corners
  // holding a (no races).
  struct Count {
    std::uint32_t vertex = UINT32_MAX;  ///< the a the count belongs to
    std::uint32_t triangles = 0;        ///< a's triangles holding x
  };
  tbb::enumerable_thread_specific<std::vector<Count>> counts_per_thread(
      [&] { return std::vector<Count>(vertex_count); });
  std::vector<std::uint8_t> leaves_border(tris.size() * 3, 0);
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, vertex_count, 1024),
                    [&](const tbb::blocked_range<std::uint32_t>& range) {
                      std::vector<Count>& counts = counts_per_thread.local();
                      for (std::uint32_t a = range.begin(); a != range.end(); ++a) {
                        const std::uint32_t *first = around.begin(a), *last = around.end(a);
                        std::uint32_t distinct =
                            0;  // a's triangles (one listed per repetition of a)
                        for (const std::uint32_t* s = first; s != last; ++s) {
                          if (s != first && *s == s[-1]) continue;
                          ++distinct;
                          const Triangle& t = tris[*s];
                          for (std::size_t i = 0; i < 3; ++i) {
                            const std::uint32_t x = t[i];
                            if (x >= vertex_count || (i > 0 && x == t[0]) || (i > 1 && x == t[1]))
                              continue;
                            Count& c = counts[x];
                            c.triangles = c.vertex == a ? c.triangles + 1 : 1;
                            c.vertex = a;
                          }
                        }
                        for (const std::uint32_t* s = first; s != last; ++s) {
                          if (s != first && *s == s[-1]) continue;
                          const Triangle& t = tris[*s];
                          for (std::size_t i = 0; i < 3; ++i) {
                            if (t[i] != a) continue;
                            const std::uint32_t b = t[(i + 1) % 3];
                            // Only this triangle holds b (every one of a's holds b = a).
                            const std::uint32_t holding = b == a             ? distinct
                                                          : b < vertex_count ? counts[b].triangles
                                                                             : 1;
                            leaves_border[std::size_t{*s} * 3 + i] = holding == 1 ? 1 : 0;
                          }
                        }
                      }
                    });
  const std::vector<std::uint32_t> selected = parallel_select_indices(
      tris.size() * 3, [&](std::size_t c) { return leaves_border[c] != 0; });
  std::vector<BorderEdge> border(selected.size());
  tbb::parallel_for(std::size_t{0}, selected.size(), [&](std::size_t k) {
    const std::uint32_t t = selected[k] / 3;
    const std::size_t i = selected[k] % 3;
    border[k] = BorderEdge{tris[t][i], tris[t][(i + 1) % 3], t};
  });
  return border;
}

float median_edge_length(const TriangleMesh& mesh) {
  // Squared lengths: the square root is monotonic, so the median's root is the median of the
  // roots (the same float), for one root instead of one per edge.
  if (mesh.triangles.empty()) return 0.0f;
  std::vector<float> squared(3 * mesh.triangles.size());
  tbb::parallel_for(std::size_t{0}, mesh.triangles.size(), [&](std::size_t i) {
    const Triangle& t = mesh.triangles[i];
    for (std::size_t k = 0; k < 3; ++k)
      squared[3 * i + k] = (mesh.vertices[t[(k + 1) % 3]] - mesh.vertices[t[k]]).squaredNorm();
  });
  const auto middle = squared.begin() + static_cast<std::ptrdiff_t>(squared.size() / 2);
  std::nth_element(squared.begin(), middle, squared.end());
  return std::sqrt(*middle);
}

TriangleMesh compact_vertices(const TriangleMesh& source, const std::vector<Triangle>& triangles,
                              std::vector<std::uint32_t>* original) {
  const std::size_t n = source.vertices.size();
  // Which vertices the triangles use (relaxed stores of the same value: no order needed).
  std::vector<std::atomic<std::uint8_t>> used(n);
  tbb::parallel_for(std::size_t{0}, triangles.size(), [&](std::size_t i) {
    for (std::uint32_t v : triangles[i]) used[v].store(1, std::memory_order_relaxed);
  });
  const std::vector<std::uint32_t> kept = parallel_select_indices(
      n, [&](std::size_t v) { return used[v].load(std::memory_order_relaxed) != 0; });
  const bool normals = source.normals.size() == n;
  const bool colors = source.colors.size() == n;
  TriangleMesh out;
  out.vertices.resize(kept.size());
  if (normals) out.normals.resize(kept.size());
  if (colors) out.colors.resize(kept.size());
  std::vector<std::uint32_t> id(n);
  tbb::parallel_for(std::size_t{0}, kept.size(), [&](std::size_t i) {
    const std::uint32_t v = kept[i];
    id[v] = static_cast<std::uint32_t>(i);
    out.vertices[i] = source.vertices[v];
    if (normals) out.normals[i] = source.normals[v];
    if (colors) out.colors[i] = source.colors[v];
  });
  out.triangles.resize(triangles.size());
  tbb::parallel_for(std::size_t{0}, triangles.size(), [&](std::size_t i) {
    const Triangle& t = triangles[i];
    out.triangles[i] = Triangle{id[t[0]], id[t[1]], id[t[2]]};
  });
  if (original != nullptr) *original = kept;
  return out;
}

std::vector<std::uint32_t> renumber_used_vertices(std::vector<Triangle>& triangles,
                                                  std::size_t vertex_count) {
  // A byte mask (every writer stores the same 1: a quarter of the memory traffic of marking ids),
  // the used vertices selected in order, then each one's new id written at its old index only.
  std::vector<std::uint8_t> used(vertex_count, 0);
  tbb::parallel_for(std::size_t{0}, triangles.size(), [&](std::size_t t) {
    for (std::uint32_t v : triangles[t]) __atomic_store_n(&used[v], 1, __ATOMIC_RELAXED);
  });
  std::vector<std::uint32_t> original =
      parallel_select_indices(vertex_count, [&used](std::size_t v) { return used[v] != 0; });
  std::unique_ptr<std::uint32_t[]> renumbered(new std::uint32_t[vertex_count]);
  tbb::parallel_for(std::size_t{0}, original.size(), [&](std::size_t i) {
    renumbered[original[i]] = static_cast<std::uint32_t>(i);
  });
  tbb::parallel_for(std::size_t{0}, triangles.size(), [&](std::size_t t) {
    for (std::uint32_t& v : triangles[t]) v = renumbered[v];
  });
  return original;
}

void remove_small_components(std::vector<Triangle>& triangles, std::size_t vertex_count,
                             std::size_t min_triangles, ComponentCounts* counts,
                             const std::vector<std::uint8_t>* held) {
  const std::vector<std::uint32_t> component = vertex_component_labels(triangles, vertex_count);
  std::vector<std::uint32_t> component_size(vertex_count, 0);
  for (const Triangle& t : triangles) ++component_size[component[t[0]]];
  if (held != nullptr)  // a component with a held vertex stays: counted as large enough
    for (const Triangle& t : triangles)
      for (const std::uint32_t v : t)
        if (v < held->size() && (*held)[v] != 0) {
          std::uint32_t& size = component_size[component[v]];
          size = std::max<std::uint32_t>(size, static_cast<std::uint32_t>(min_triangles));
        }
  ComponentCounts c;
  for (std::uint32_t s : component_size) {
    if (s == 0) continue;
    ++c.components;
    if (s < min_triangles) {
      ++c.removed_components;
      c.removed_triangles += s;
    }
  }
  if (counts != nullptr) {
    counts->components += c.components;
    counts->removed_components += c.removed_components;
    counts->removed_triangles += c.removed_triangles;
  }
  if (c.removed_components == 0) return;
  triangles.erase(std::remove_if(triangles.begin(), triangles.end(),
                                 [&](const Triangle& t) {
                                   return component_size[component[t[0]]] < min_triangles;
                                 }),
                  triangles.end());
}

void require_corners_in_range(const std::vector<Triangle>& triangles, std::size_t vertex_count,
                              const std::string& source) {
  for (std::size_t f = 0; f < triangles.size(); ++f)
    for (std::uint32_t v : triangles[f])
      if (v >= vertex_count)
        throw Error(source, "face " + std::to_string(f),
                    "vertex index " + std::to_string(v) + " out of range (" +
                        std::to_string(vertex_count) + " vertices)");
}

}  // namespace meshflow
