#include "nodes/optimize/cleanup/manifold_repair.h"

#include <tbb/parallel_for.h>

#include <vector>

#include "runtime/vertex_triangles.h"

namespace meshflow {

std::size_t split_non_manifold_vertices(TriangleMesh& mesh) {
  const std::size_t n = mesh.vertices.size();
  const VertexTriangles around = vertex_triangles(mesh);
  // All fans first (reading the triangles), then the rewrite.
  std::vector<std::uint32_t> fan;
  std::vector<std::uint32_t> extra = vertex_fans(mesh.triangles, around, fan);
  for (std::uint32_t& fans : extra) fans = fans > 1 ? fans - 1 : 0;
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
