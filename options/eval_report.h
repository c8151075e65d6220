#pragma once
// What `meshflow eval MESH --reference REF` measures, apart from printing it: shared by the CLI
// and the Python module (meshflow.evaluate), so both give the same figures.

#include <nlohmann/json.hpp>

#include <string>

#include "nodes/eval/surface_eval.h"
#include "runtime/triangle_mesh.h"

namespace meshflow::options {

/// Double walls within `radius` metres (the radius used: the median edge length when 0 was
/// asked for) and the share of the mesh's area (0..1) they cover.
struct DoubleWalls {
  float radius = 0.0f;
  double share = 0.0;
};

/// Double walls of `mesh` within `radius` metres (0: the median edge length). O(T log T).
DoubleWalls double_walls(const TriangleMesh& mesh, float radius);

/// {"radius", "area_share"}.
nlohmann::json double_walls_json(const DoubleWalls& w);

/// A watertight mesh's orientation from its enclosed volume (m^3): "outward" or "inside out";
/// nullptr for a mesh that is not watertight.
const char* closed_orientation(const MeshTopology& t, double volume);

/// A reference file as eval reads it: a mesh file (.ply .obj .off .stl) as a mesh (a PLY
/// without faces is a point set); any other point-cloud file as a point set (NaN points
/// skipped). Throws meshflow::Error naming the file.
TriangleMesh read_reference(const std::string& path);

/// Everything eval reports against a reference.
struct ReferenceEvaluation {
  SurfaceEvaluation surface;
  DoubleWalls walls;
  const char* orientation = nullptr;  ///< closed_orientation(); nullptr: not watertight
  std::size_t reference_points = 0, reference_triangles = 0;
};

/// Evaluates `mesh` against `reference` (evaluate_surface, double walls within `wall_radius`
/// metres, 0 = the median edge length, orientation). Throws meshflow::Error for an empty mesh
/// or reference. Parallel, deterministic.
ReferenceEvaluation evaluate_reference(const TriangleMesh& mesh, const TriangleMesh& reference,
                                       float wall_radius);

/// eval's --json document: "mesh", "vertices", "triangles", "reference" {"file", "points",
/// "triangles"}, "mesh_to_reference", "reference_to_mesh", "topology",
/// "normal_deviation_deg" {"mean", "p95"} (null without reference normals),
/// "inside_out_area_share", "orientation", "double_walls".
nlohmann::json reference_evaluation_json(const ReferenceEvaluation& r, const std::string& mesh_name,
                                         const std::string& reference_name);

}  // namespace meshflow::options
