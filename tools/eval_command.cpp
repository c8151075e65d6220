// meshflow eval MESH --reference CLOUD_OR_MESH: distances both ways, normals, topology; or
// --object NAME: distances to a built-in object's exact surface.

#include <cstdio>
#include <memory>
#include <string>

#include "nodes/eval/surface_eval.h"
#include "nodes/eval/truth_eval.h"
#include "nodes/io/ply_reader.h"
#include "nodes/io/read_point_cloud.h"
#include "nodes/synthetic/closed_objects.h"
#include "runtime/error.h"
#include "tools/commands.h"

namespace meshflow::cli {
namespace {

bool has_ply_extension(const std::string& path) {
  return path.size() >= 4 && (path.compare(path.size() - 4, 4, ".ply") == 0 ||
                              path.compare(path.size() - 4, 4, ".PLY") == 0);
}

// A PLY file with faces is a mesh; any other point-cloud file is a point set.
TriangleMesh read_reference(const std::string& path) {
  if (has_ply_extension(path)) return io::read_ply_mesh(path);
  PointCloud cloud = io::read_point_cloud(path);
  TriangleMesh points;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!cloud.positions[i].allFinite()) continue;  // scans mark missing returns with NaN
    points.vertices.push_back(cloud.positions[i]);
    if (cloud.has_normals()) points.normals.push_back(cloud.normals[i]);
  }
  return points;
}

void print_distances(const char* label, const DistanceStats& s) {
  std::printf("%-18s mean %.6f  rms %.6f  median %.6f  p95 %.6f  max %.6f m  (%zu samples)\n",
              label, s.mean, s.rms, s.median, s.p95, s.max, s.samples);
}

// Distances to the exact surface of a built-in object, also relative to its diagonal.
void print_truth_evaluation(const std::string& path, const TriangleMesh& mesh,
                            const synthetic::ClosedObject& object) {
  const TruthEvaluation e = evaluate_against_truth(
      mesh, [&object](const Eigen::Vector3f& p) { return object.distance(p); });
  const double diagonal = object.diagonal();
  std::printf("mesh               %s: %zu vertices, %zu triangles\n", path.c_str(),
              mesh.vertices.size(), mesh.triangles.size());
  std::printf("reference          the exact surface of '%s' (diagonal %.4f m)\n",
              object.name.c_str(), diagonal);
  print_distances("vertices -> truth", e.vertices);
  print_distances("surface -> truth", e.area);
  std::printf("of the diagonal    surface mean %.2e  p95 %.2e  (vertices mean %.2e  p95 %.2e)\n",
              e.area.mean / diagonal, e.area.p95 / diagonal, e.vertices.mean / diagonal,
              e.vertices.p95 / diagonal);
  const MeshTopology& t = e.topology;
  std::printf(
      "topology           %zu edges, %zu boundary, %zu non-manifold, %zu inconsistent; "
      "%zu boundary loops, %zu degenerate faces%s\n",
      t.edges.edges, t.edges.boundary_edges, t.edges.non_manifold_edges, t.edges.inconsistent_edges,
      t.boundary_loops, t.degenerate_faces,
      t.edges.closed() && t.edges.inconsistent_edges == 0 ? " (watertight)" : "");
}

}  // namespace

void add_eval_command(CLI::App& app) {
  auto mesh_path = std::make_shared<std::string>();
  auto reference_path = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "eval", "Compare a mesh with a reference point cloud or mesh (distances, normals, topology)");
  cmd->add_option("mesh", *mesh_path, "Mesh to evaluate (PLY with faces)")->required();
  auto object_name = std::make_shared<std::string>();
  auto* reference_option = cmd->add_option(
      "--reference", *reference_path, "Reference: a PLY mesh, or any point cloud meshflow reads");
  auto* object_option =
      cmd->add_option("--object", *object_name,
                      "Or the exact surface of a built-in object (meshflow sample)")
          ->check(CLI::IsMember(closed_object_names()));
  reference_option->excludes(object_option);
  cmd->callback([mesh_path, reference_path, object_name] {
    const TriangleMesh mesh = io::read_ply_mesh(*mesh_path);
    if (mesh.triangles.empty()) throw Error(*mesh_path, "face", "the file has no triangles");
    if (!object_name->empty()) {
      print_truth_evaluation(*mesh_path, mesh, *synthetic::closed_test_object(*object_name));
      return;
    }
    if (reference_path->empty())
      throw CLI::ValidationError("eval", "give --reference FILE or --object NAME");
    const TriangleMesh reference = read_reference(*reference_path);
    const SurfaceEvaluation e = evaluate_surface(mesh, reference);
    std::printf("mesh               %s: %zu vertices, %zu triangles\n", mesh_path->c_str(),
                e.vertices, e.triangles);
    std::printf("reference          %s: %zu points%s\n", reference_path->c_str(),
                reference.vertices.size(),
                reference.triangles.empty()
                    ? ""
                    : (", " + std::to_string(reference.triangles.size()) + " triangles").c_str());
    print_distances("mesh -> reference", e.mesh_to_reference);
    print_distances("reference -> mesh", e.reference_to_mesh);
    if (e.normal_samples > 0) {
      std::printf("normal deviation   mean %.2f  p95 %.2f degrees (orientation ignored)\n",
                  e.normal_mean_deg, e.normal_p95_deg);
    } else {
      std::printf("normal deviation   n/a (the reference has no normals)\n");
    }
    const MeshTopology& t = e.topology;
    std::printf(
        "topology           %zu edges, %zu boundary, %zu non-manifold, %zu inconsistent; "
        "%zu boundary loops, %zu degenerate faces\n",
        t.edges.edges, t.edges.boundary_edges, t.edges.non_manifold_edges,
        t.edges.inconsistent_edges, t.boundary_loops, t.degenerate_faces);
  });
}

}  // namespace meshflow::cli
