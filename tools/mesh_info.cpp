// `meshflow info MESH`: the statistics of a mesh file (nodes/eval/mesh_statistics.h), printed
// or as --json (docs/JSON.md).

#include <nlohmann/json.hpp>

#include <string>

#include "nodes/eval/mesh_statistics.h"
#include "nodes/io/mesh_readers.h"
#include "nodes/io/parse_util.h"
#include "nodes/io/ply_reader.h"
#include "tools/commands.h"
#include "tools/console.h"

namespace meshflow::cli {
namespace {

nlohmann::json mesh_info_json(const std::string& path, const TriangleMesh& mesh,
                              const MeshStatistics& s) {
  const auto vec = [](const Eigen::Vector3f& v) { return nlohmann::json{v.x(), v.y(), v.z()}; };
  const EdgeStatistics& e = s.topology.edges;
  nlohmann::json doc = {
      {"file", path},
      {"kind", "mesh"},
      {"vertices", s.vertices},
      {"referenced_vertices", s.referenced_vertices},
      {"triangles", s.triangles},
      {"fields",
       {{"normals", mesh.normals.size() == mesh.vertices.size() && !mesh.vertices.empty()},
        {"colors", mesh.colors.size() == mesh.vertices.size() && !mesh.vertices.empty()}}},
      {"area_m2", s.area},
      {"closed", s.closed},
      {"volume_m3", nullptr},
      {"orientation", nullptr},
      {"euler_characteristic", s.euler_characteristic},
      {"genus", nullptr},
      {"components", s.components},
      {"border_loops", s.topology.boundary_loops},
      {"edges", e.edges},
      {"border_edges", e.boundary_edges},
      {"non_manifold_edges", e.non_manifold_edges},
      {"non_manifold_vertices", s.non_manifold_vertices},
      {"inconsistent_edges", e.inconsistent_edges},
      {"degenerate_triangles", s.topology.degenerate_faces}};
  if (s.volume) {
    doc["volume_m3"] = *s.volume;
    doc["orientation"] = *s.volume >= 0.0 ? "outward" : "inside out";
  }
  if (s.genus) doc["genus"] = *s.genus;
  if (!s.bounds.isEmpty())
    doc["bounds"] = {{"min", vec(s.bounds.min())}, {"max", vec(s.bounds.max())}};
  return doc;
}

void print_mesh_info(const std::string& path, const TriangleMesh& mesh, const MeshStatistics& s) {
  const EdgeStatistics& e = s.topology.edges;
  report("file        %s\n", path.c_str());
  report("mesh        %zu vertices (%zu used by triangles), %zu triangles%s%s\n", s.vertices,
         s.referenced_vertices, s.triangles,
         mesh.normals.size() == mesh.vertices.size() && !mesh.vertices.empty() ? ", normals" : "",
         mesh.colors.size() == mesh.vertices.size() && !mesh.vertices.empty() ? ", colours" : "");
  report("area        %.6g m^2\n", s.area);
  if (s.volume)
    report("volume      %.6g m^3 (closed, faces %s)\n", std::abs(*s.volume),
           *s.volume >= 0.0 ? "outward" : "inside out");
  else
    report("volume      - (not closed: %zu border edges, %zu non-manifold, %zu inconsistent)\n",
           e.boundary_edges, e.non_manifold_edges, e.inconsistent_edges);
  report("topology    Euler characteristic %lld, ", s.euler_characteristic);
  if (s.genus)
    report("genus %lld\n", *s.genus);
  else
    report("genus - (not an oriented manifold)\n");
  report("components  %zu\n", s.components);
  report("borders     %zu loops (%zu edges)\n", s.topology.boundary_loops, e.boundary_edges);
  report(
      "manifold    %s: %zu non-manifold edges, %zu non-manifold vertices, %zu inconsistent "
      "edges\n",
      e.non_manifold_edges == 0 && s.non_manifold_vertices == 0 ? "yes" : "no",
      e.non_manifold_edges, s.non_manifold_vertices, e.inconsistent_edges);
  report("degenerate  %zu triangles (a repeated corner or no area)\n", s.topology.degenerate_faces);
  if (!s.bounds.isEmpty()) {
    const Eigen::AlignedBox3f& b = s.bounds;
    report("bounds min  %.4f %.4f %.4f m\n", b.min().x(), b.min().y(), b.min().z());
    report("bounds max  %.4f %.4f %.4f m\n", b.max().x(), b.max().y(), b.max().z());
    report("extent      %.4f x %.4f x %.4f m\n", b.sizes().x(), b.sizes().y(), b.sizes().z());
  }
}

}  // namespace

bool is_mesh_info_file(const std::string& path) {
  const std::string ext = io::lower_extension(path);
  if (ext == ".ply") return io::ply_has_faces(path);
  return ext != ".mfc" && io::is_mesh_file(path);
}

void run_mesh_info(const std::string& path) {
  const TriangleMesh mesh = io::read_mesh(path);
  const MeshStatistics s = mesh_statistics(mesh);
  if (console().json) return print_json(mesh_info_json(path, mesh, s));
  print_mesh_info(path, mesh, s);
}

}  // namespace meshflow::cli
