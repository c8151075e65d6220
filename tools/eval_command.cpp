// meshflow eval MESH --reference CLOUD_OR_MESH: distances both ways, normals, topology.

#include <cstdio>
#include <memory>
#include <string>

#include "nodes/eval/surface_eval.h"
#include "nodes/io/ply_reader.h"
#include "nodes/io/read_point_cloud.h"
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

}  // namespace

void add_eval_command(CLI::App& app) {
  auto mesh_path = std::make_shared<std::string>();
  auto reference_path = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "eval", "Compare a mesh with a reference point cloud or mesh (distances, normals, topology)");
  cmd->add_option("mesh", *mesh_path, "Mesh to evaluate (PLY with faces)")->required();
  cmd->add_option("--reference", *reference_path,
                  "Reference: a PLY mesh, or any point cloud meshflow reads")
      ->required();
  cmd->callback([mesh_path, reference_path] {
    const TriangleMesh mesh = io::read_ply_mesh(*mesh_path);
    if (mesh.triangles.empty()) throw Error(*mesh_path, "face", "the file has no triangles");
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
