#include "options/eval_report.h"

#include <cmath>

#include "nodes/eval/double_walls.h"
#include "nodes/io/mesh_readers.h"
#include "nodes/io/read_point_cloud.h"
#include "options/json_report.h"

namespace meshflow::options {

DoubleWalls double_walls(const TriangleMesh& mesh, float radius) {
  const float r = radius > 0.0f ? radius : median_edge_length(mesh);
  return {r, double_wall_area_share(mesh, r)};
}

nlohmann::json double_walls_json(const DoubleWalls& w) {
  return {{"radius", w.radius}, {"area_share", w.share}};
}

const char* closed_orientation(const MeshTopology& t, double volume) {
  if (!t.edges.closed() || t.edges.inconsistent_edges > 0) return nullptr;
  return volume >= 0.0 ? "outward" : "inside out";
}

TriangleMesh read_reference(const std::string& path) {
  if (io::is_mesh_file(path)) return io::read_mesh(path);
  PointCloud cloud = io::read_point_cloud(path);
  TriangleMesh points;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!cloud.positions[i].allFinite()) continue;  // scans mark missing returns with NaN
    points.vertices.push_back(cloud.positions[i]);
    if (cloud.has_normals()) points.normals.push_back(cloud.normals[i]);
  }
  return points;
}

ReferenceEvaluation evaluate_reference(const TriangleMesh& mesh, const TriangleMesh& reference,
                                       float wall_radius) {
  ReferenceEvaluation r;
  r.surface = evaluate_surface(mesh, reference);
  r.walls = double_walls(mesh, wall_radius);
  r.orientation = closed_orientation(r.surface.topology, signed_volume(mesh));
  r.reference_points = reference.vertices.size();
  r.reference_triangles = reference.triangles.size();
  return r;
}

nlohmann::json reference_evaluation_json(const ReferenceEvaluation& r, const std::string& mesh_name,
                                         const std::string& reference_name) {
  const SurfaceEvaluation& e = r.surface;
  nlohmann::json doc = {{"mesh", mesh_name},
                        {"vertices", e.vertices},
                        {"triangles", e.triangles},
                        {"reference",
                         {{"file", reference_name},
                          {"points", r.reference_points},
                          {"triangles", r.reference_triangles}}},
                        {"mesh_to_reference", distance_json(e.mesh_to_reference)},
                        {"reference_to_mesh", distance_json(e.reference_to_mesh)},
                        {"topology", topology_json(e.topology)}};
  doc["normal_deviation_deg"] =
      e.normal_samples > 0 ? nlohmann::json{{"mean", e.normal_mean_deg}, {"p95", e.normal_p95_deg}}
                           : nlohmann::json();
  doc["inside_out_area_share"] = std::isnan(e.inside_out_area_share)
                                     ? nlohmann::json()
                                     : nlohmann::json(e.inside_out_area_share);
  doc["orientation"] = r.orientation != nullptr ? nlohmann::json(r.orientation) : nlohmann::json();
  doc["double_walls"] = double_walls_json(r.walls);
  return doc;
}

}  // namespace meshflow::options
