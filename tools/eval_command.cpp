// meshflow eval MESH --reference CLOUD_OR_MESH: distances both ways, normals, orientation,
// topology; or --object NAME: distances to a built-in object's exact surface.

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "nodes/eval/surface_eval.h"
#include "nodes/eval/truth_eval.h"
#include "nodes/io/mesh_readers.h"
#include "nodes/io/read_point_cloud.h"
#include "nodes/synthetic/closed_objects.h"
#include "options/eval_report.h"
#include "options/json_report.h"
#include "runtime/error.h"
#include "tools/cli_checks.h"
#include "tools/commands.h"
#include "tools/console.h"

namespace meshflow::cli {
namespace {

void print_distances(const char* label, const DistanceStats& s) {
  report("%-18s mean %.6f  rms %.6f  median %.6f  p95 %.6f  max %.6f m  (%zu samples)\n", label,
         s.mean, s.rms, s.median, s.p95, s.max, s.samples);
}

void print_topology(const MeshTopology& t) {
  report(
      "topology           %zu edges, %zu boundary, %zu non-manifold, %zu inconsistent; "
      "%zu boundary loops, %zu degenerate faces%s\n",
      t.edges.edges, t.edges.boundary_edges, t.edges.non_manifold_edges, t.edges.inconsistent_edges,
      t.boundary_loops, t.degenerate_faces,
      t.edges.closed() && t.edges.inconsistent_edges == 0 ? " (watertight)" : "");
}

void print_double_walls(const options::DoubleWalls& w) {
  report("double walls       %.2f %% of the area within %.4g m of another sheet\n", 100.0 * w.share,
         w.radius);
}

// Distances to the exact surface of a built-in object, also relative to its diagonal.
void evaluate_object(const std::string& path, const TriangleMesh& mesh,
                     const synthetic::ClosedObject& object, float wall_radius) {
  const options::DoubleWalls walls = options::double_walls(mesh, wall_radius);
  const TruthEvaluation e = evaluate_against_truth(
      mesh, [&object](const Eigen::Vector3f& p) { return object.distance(p); });
  const double diagonal = object.diagonal();
  const char* orientation = options::closed_orientation(e.topology, signed_volume(mesh));
  if (console().json) {
    nlohmann::json doc = {{"mesh", path},
                          {"vertices", mesh.vertices.size()},
                          {"triangles", mesh.triangles.size()},
                          {"reference", {{"object", object.name}, {"diagonal", diagonal}}},
                          {"vertices_to_truth", options::distance_json(e.vertices)},
                          {"surface_to_truth", options::distance_json(e.area)},
                          {"relative_to_diagonal",
                           {{"surface_mean", e.area.mean / diagonal},
                            {"surface_p95", e.area.p95 / diagonal},
                            {"vertices_mean", e.vertices.mean / diagonal},
                            {"vertices_p95", e.vertices.p95 / diagonal}}},
                          {"topology", options::topology_json(e.topology)}};
    doc["orientation"] = orientation != nullptr ? nlohmann::json(orientation) : nlohmann::json();
    doc["double_walls"] = options::double_walls_json(walls);
    return print_json(doc);
  }
  report("mesh               %s: %zu vertices, %zu triangles\n", path.c_str(), mesh.vertices.size(),
         mesh.triangles.size());
  report("reference          the exact surface of '%s' (diagonal %.4f m)\n", object.name.c_str(),
         diagonal);
  print_distances("vertices -> truth", e.vertices);
  print_distances("surface -> truth", e.area);
  report("of the diagonal    surface mean %.2e  p95 %.2e  (vertices mean %.2e  p95 %.2e)\n",
         e.area.mean / diagonal, e.area.p95 / diagonal, e.vertices.mean / diagonal,
         e.vertices.p95 / diagonal);
  print_topology(e.topology);
  if (orientation != nullptr) report("orientation        %s (enclosed volume)\n", orientation);
  print_double_walls(walls);
}

void print_reference_evaluation(const std::string& mesh_path, const TriangleMesh& mesh,
                                const std::string& reference_path, float wall_radius) {
  const TriangleMesh reference = options::read_reference(reference_path);
  const options::ReferenceEvaluation r = options::evaluate_reference(mesh, reference, wall_radius);
  if (console().json)
    return print_json(options::reference_evaluation_json(r, mesh_path, reference_path));
  const SurfaceEvaluation& e = r.surface;
  report("mesh               %s: %zu vertices, %zu triangles\n", mesh_path.c_str(), e.vertices,
         e.triangles);
  report("reference          %s: %zu points%s\n", reference_path.c_str(), r.reference_points,
         r.reference_triangles == 0
             ? ""
             : (", " + std::to_string(r.reference_triangles) + " triangles").c_str());
  print_distances("mesh -> reference", e.mesh_to_reference);
  print_distances("reference -> mesh", e.reference_to_mesh);
  if (e.normal_samples > 0) {
    report("normal deviation   mean %.2f  p95 %.2f degrees (orientation ignored)\n",
           e.normal_mean_deg, e.normal_p95_deg);
    report("inside out         %.1f %% of the area faces against the reference's normals\n",
           100.0 * e.inside_out_area_share);
  } else {
    report("normal deviation   n/a (the reference has no normals)\n");
  }
  print_topology(e.topology);
  if (r.orientation != nullptr) report("orientation        %s (enclosed volume)\n", r.orientation);
  print_double_walls(r.walls);
}

}  // namespace

void add_eval_options(CLI::App* cmd) {
  auto mesh_path = std::make_shared<std::string>();
  auto reference_path = std::make_shared<std::string>();
  cmd->add_option("mesh", *mesh_path, "Mesh to evaluate: .ply .obj .off .stl")->required();
  auto object_name = std::make_shared<std::string>();
  auto* reference_option =
      cmd->add_option("--reference", *reference_path,
                      "Reference: a mesh (.ply .obj .off .stl), or any point cloud meshflow reads");
  auto* object_option =
      cmd->add_option("--object", *object_name,
                      "Or the exact surface of a built-in object (meshflow sample)")
          ->check(CLI::IsMember(closed_object_names()));
  reference_option->excludes(object_option);
  auto wall_radius = std::make_shared<float>(0.0f);
  cmd->add_option("--wall-radius", *wall_radius,
                  "Double walls: parts of the mesh closer than this (metres) that are 3x as far "
                  "apart along the mesh (auto, 0: the median edge length)")
      ->check(number_in(0, 1e6))
      ->default_str("auto");
  add_console_flags(cmd, true);
  cmd->callback([mesh_path, reference_path, object_name, wall_radius] {
    const TriangleMesh mesh = io::read_mesh(*mesh_path);
    if (mesh.triangles.empty()) throw Error(*mesh_path, "face", "the file has no triangles");
    if (!object_name->empty())
      return evaluate_object(*mesh_path, mesh, *synthetic::closed_test_object(*object_name),
                             *wall_radius);
    if (reference_path->empty())
      throw CLI::ValidationError("eval", "give --reference FILE or --object NAME");
    print_reference_evaluation(*mesh_path, mesh, *reference_path, *wall_radius);
  });
}

}  // namespace meshflow::cli
