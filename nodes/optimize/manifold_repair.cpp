#include "nodes/optimize/manifold_repair.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <utility>
#include <vector>

#include "runtime/disjoint_sets.h"
#include "runtime/vertex_triangles.h"

namespace meshflow {
namespace {

// The working memory of fans_around(), reused from vertex to vertex by one task.
struct FanScratch {
  DisjointSets sets{0};
  std::vector<std::pair<std::uint32_t, std::uint32_t>> spokes;  ///< (x, triangle slot)
  std::vector<std::uint32_t> number;                            ///< fan number of each root
};

// Writes the fan of each triangle around v to fan[0 .. k) (0 = the fan with the lowest triangle
// index, then in order of their lowest triangles), given the k triangles around v in ascending
// order. Returns the fan count.
std::uint32_t fans_around(const TriangleMesh& mesh, std::uint32_t v, const std::uint32_t* begin,
                          const std::uint32_t* end, std::uint32_t* fan, FanScratch& scratch) {
  const auto k = static_cast<std::uint32_t>(end - begin);
  auto& [sets, spokes, number] = scratch;
  sets.reset(k);
  // Triangles sharing an edge v-x are in one fan: sort (x, triangle slot) and join equal x.
  spokes.clear();
  for (std::uint32_t i = 0; i < k; ++i)
    for (std::uint32_t x : mesh.triangles[begin[i]])
      if (x != v) spokes.emplace_back(x, i);
  std::sort(spokes.begin(), spokes.end());
  for (std::size_t s = 1; s < spokes.size(); ++s)
    if (spokes[s].first == spokes[s - 1].first) sets.unite(spokes[s].second, spokes[s - 1].second);
  // Roots are the lowest slot of their fan, so numbering roots in slot order numbers fans by
  // their lowest triangle.
  number.assign(k, 0);
  std::uint32_t fans = 0;
  for (std::uint32_t i = 0; i < k; ++i) {
    const std::uint32_t r = sets.find(i);
    if (r == i) number[i] = fans++;
    fan[i] = number[r];
  }
  return fans;
}

}  // namespace

std::size_t split_non_manifold_vertices(TriangleMesh& mesh) {
  const std::size_t n = mesh.vertices.size();
  const VertexTriangles around = vertex_triangles(mesh);
  // All fans first (reading the triangles), then the rewrite.
  std::vector<std::uint32_t> fan(around.triangles.size()), extra(n, 0);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& range) {
        FanScratch scratch;
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
