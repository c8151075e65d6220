#include "nodes/optimize/cleanup/manifold_repair.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <numeric>
#include <utility>
#include <vector>

#include "runtime/vertex_triangles.h"

namespace meshflow {
namespace {

// The working memory of fans_around(), reused from vertex to vertex by one thread.
struct FanScratch {
  /// Per vertex x: the vertex v whose fans were last looked at with x as a spoke, and the slot of
  /// the latest of v's triangles holding x (stamped with v: nothing is cleared between vertices).
  struct Spoke {
    std::uint32_t vertex = UINT32_MAX, slot = 0;
  };
  std::vector<Spoke> spokes;
  std::vector<std::uint32_t> parent;  ///< union-find over the slots of v's triangles
};

// Writes the fan of each triangle around v to fan[0 .. k) (0 = the fan with the lowest triangle
// index, then in order of their lowest triangles), given the k triangles around v in ascending
// order. Triangles sharing an edge v-x (a corner x other than v) are in one fan: each spoke x
// joins the triangle holding it to the previous one that did. Returns the fan count. O(k).
std::uint32_t fans_around(const TriangleMesh& mesh, std::uint32_t v, const std::uint32_t* begin,
                          const std::uint32_t* end, std::uint32_t* fan, FanScratch& scratch) {
  const auto k = static_cast<std::uint32_t>(end - begin);
  auto& spokes = scratch.spokes;
  auto& parent = scratch.parent;  // (a reference, not a structured binding: lambdas capture it)
  parent.resize(k);
  std::iota(parent.begin(), parent.end(), 0u);
  // Union-find with path halving whose roots are the lowest slot of their set.
  const auto find = [&parent](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (std::uint32_t i = 0; i < k; ++i)
    for (std::uint32_t x : mesh.triangles[begin[i]]) {
      if (x == v || x >= spokes.size()) continue;  // (an index past the vertices: no spoke)
      FanScratch::Spoke& spoke = spokes[x];
      if (spoke.vertex == v) {  // joined with the previous of v's triangles holding x
        const std::uint32_t a = find(i), b = find(spoke.slot);
        parent[std::max(a, b)] = std::min(a, b);
      }
      spoke = {v, i};
    }
  // A root is its fan's lowest slot, so slots in order meet each root before its other members.
  std::uint32_t fans = 0;
  for (std::uint32_t i = 0; i < k; ++i) {
    const std::uint32_t r = find(i);
    fan[i] = r == i ? fans++ : fan[r];
  }
  return fans;
}

}  // namespace

std::size_t split_non_manifold_vertices(TriangleMesh& mesh) {
  const std::size_t n = mesh.vertices.size();
  const VertexTriangles around = vertex_triangles(mesh);
  // All fans first (reading the triangles), then the rewrite.
  std::vector<std::uint32_t> fan(around.triangles.size()), extra(n, 0);
  tbb::enumerable_thread_specific<FanScratch> scratch_per_thread([n] {
    FanScratch scratch;
    scratch.spokes.resize(n);
    return scratch;
  });
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& range) {
        FanScratch& scratch = scratch_per_thread.local();
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
          const auto v = static_cast<std::uint32_t>(i);
          const std::uint32_t fans = fans_around(mesh, v, around.begin(v), around.end(v),
                                                 fan.data() + around.offsets[v], scratch);
          extra[i] = fans > 1 ? fans - 1 : 0;
        }
      });
  // extra[v] -> index of v's first new vertex.
  std::uint32_t next = static_cast<std::uint32_t>(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t count = extra[i];
    extra[i] = next;
    next += count;
  }
  const std::size_t added = next - n;
  if (added == 0) return 0;
  std::vector<std::uint32_t> source(added);
  const bool normals = mesh.normals.size() == n, colors = mesh.colors.size() == n;
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    const auto v = static_cast<std::uint32_t>(i);
    const std::uint32_t first = extra[i], count = (i + 1 < n ? extra[i + 1] : next) - first;
    for (std::uint32_t f = 0; f < count; ++f) source[first + f - n] = v;
    // Each task rewrites only the corners holding its own vertex.
    for (std::uint32_t s = around.offsets[v]; s < around.offsets[v + 1]; ++s) {
      if (fan[s] == 0) continue;
      for (std::uint32_t& corner : mesh.triangles[around.triangles[s]])
        if (corner == v) corner = first + fan[s] - 1;
    }
  });
  for (std::uint32_t v : source) {
    mesh.vertices.push_back(mesh.vertices[v]);
    if (normals) mesh.normals.push_back(mesh.normals[v]);
    if (colors) mesh.colors.push_back(mesh.colors[v]);
  }
  return added;
}

}  // namespace meshflow
