#include "nodes/eval/mesh_statistics.h"

#include <vector>

#include "runtime/vertex_triangles.h"

namespace meshflow {

MeshStatistics mesh_statistics(const TriangleMesh& mesh) {
  MeshStatistics s;
  s.vertices = mesh.vertices.size();
  s.triangles = mesh.triangles.size();
  s.topology = mesh_topology(mesh);

  std::vector<std::uint8_t> used(mesh.vertices.size(), 0);
  for (const Triangle& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[t[0]].cast<double>();
    const Eigen::Vector3d b = mesh.vertices[t[1]].cast<double>();
    const Eigen::Vector3d c = mesh.vertices[t[2]].cast<double>();
    s.area += 0.5 * (b - a).cross(c - a).norm();
    for (std::uint32_t v : t) used[v] = 1;
  }
  for (std::size_t v = 0; v < used.size(); ++v) {
    if (!used[v]) continue;
    ++s.referenced_vertices;
    s.bounds.extend(mesh.vertices[v]);
  }

  std::vector<Triangle> triangles = mesh.triangles;  // counted, not changed (limit 0)
  ComponentCounts components;
  remove_small_components(triangles, mesh.vertices.size(), 0, &components);
  s.components = components.components;

  const VertexTriangles around = vertex_triangles(mesh);
  std::vector<std::uint32_t> fan;
  for (std::uint32_t fans : vertex_fans(mesh.triangles, around, fan))
    s.non_manifold_vertices += fans > 1 ? 1 : 0;

  const EdgeStatistics& e = s.topology.edges;
  s.closed = s.triangles > 0 && e.closed() && e.inconsistent_edges == 0;
  if (s.closed) s.volume = signed_volume(mesh);
  s.euler_characteristic = static_cast<long long>(s.referenced_vertices) -
                           static_cast<long long>(e.edges) + static_cast<long long>(s.triangles);
  const long long twice_genus = 2 * static_cast<long long>(s.components) -
                                static_cast<long long>(s.topology.boundary_loops) -
                                s.euler_characteristic;
  if (e.non_manifold_edges == 0 && e.inconsistent_edges == 0 && s.non_manifold_vertices == 0 &&
      twice_genus >= 0 && twice_genus % 2 == 0)
    s.genus = twice_genus / 2;
  return s;
}

}  // namespace meshflow
