// compute_vertex_normals (declared in runtime/triangle_mesh.h).

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>

#include "runtime/triangle_mesh.h"

namespace meshflow {

void compute_vertex_normals(TriangleMesh& mesh) {
  const auto& tris = mesh.triangles;
  const std::size_t vertex_count = mesh.vertices.size();
  mesh.normals.resize(vertex_count);
  // One vertex range per worker. Each range's task scans every triangle and sums the area-
  // weighted normals of those touching its range in triangle order, so every vertex's sum is
  // formed in the same order as a serial loop would: identical results for any split.
  constexpr std::size_t kMinVerticesPerRange = 4096;
  const std::size_t ranges =
      std::clamp<std::size_t>(vertex_count / kMinVerticesPerRange, 1,
                              static_cast<std::size_t>(tbb::this_task_arena::max_concurrency()));
  tbb::parallel_for(std::size_t{0}, ranges, [&](std::size_t r) {
    const std::uint32_t lo = static_cast<std::uint32_t>(vertex_count * r / ranges);
    const std::uint32_t hi = static_cast<std::uint32_t>(vertex_count * (r + 1) / ranges);
    std::fill(mesh.normals.begin() + lo, mesh.normals.begin() + hi, Eigen::Vector3f::Zero());
    auto mine = [&](std::uint32_t v) { return v >= lo && v < hi; };
    for (const Triangle& t : tris) {
      if (!mine(t[0]) && !mine(t[1]) && !mine(t[2])) continue;
      const Eigen::Vector3f& a = mesh.vertices[t[0]];
      // The unnormalised cross product: the unit normal weighted by twice the area.
      const Eigen::Vector3f n = (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a);
      for (std::uint32_t v : t)
        if (mine(v)) mesh.normals[v] += n;
    }
    for (std::uint32_t v = lo; v < hi; ++v) {
      const float len = mesh.normals[v].norm();
      mesh.normals[v] =
          len > 0.0f ? Eigen::Vector3f(mesh.normals[v] / len) : Eigen::Vector3f::Zero();
    }
  });
}

}  // namespace meshflow
