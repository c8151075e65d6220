#pragma once
// Quality of a reconstructed mesh against a reference (a point set or a mesh): distances in
// both directions, normal deviation and topology counts. Shared by `meshflow eval`, the tests
// and the benchmarks.

#include <cstddef>
#include <vector>

#include "runtime/triangle_mesh.h"

namespace meshflow {

struct DistanceStats {
  double mean = 0.0, rms = 0.0, median = 0.0, p95 = 0.0, max = 0.0;  ///< metres
  std::size_t samples = 0;
};

/// Statistics of a list of distances (median, p95: the values below which 50 % and 95 % lie,
/// nearest rank).
DistanceStats distance_stats(std::vector<float> distances);

struct MeshTopology {
  EdgeStatistics edges;
  std::size_t boundary_loops = 0;    ///< connected chains of boundary edges
  std::size_t degenerate_faces = 0;  ///< a repeated vertex or zero area
};

/// O(T log T).
MeshTopology mesh_topology(const TriangleMesh& mesh);

struct SurfaceEvaluation {
  DistanceStats mesh_to_reference;  ///< from every mesh vertex to the reference
  DistanceStats reference_to_mesh;  ///< from every reference point (vertex) to the mesh surface
  /// Angle in degrees between each mesh vertex normal and the reference normal at the nearest
  /// reference point (or face), ignoring orientation (normals of scans may face either way).
  double normal_mean_deg = 0.0, normal_p95_deg = 0.0;
  std::size_t normal_samples = 0;  ///< 0 when the reference has no normals
  /// Share of the mesh's area (0..1) whose faces, by their winding, point against the
  /// reference's normal at the nearest reference point or face: an inside-out mesh gives ~1.
  /// Meaningful when the reference's normals are oriented (a mesh's faces, outward normals);
  /// NaN when the reference has no normals.
  double inside_out_area_share = 0.0;
  std::size_t vertices = 0, triangles = 0;
  MeshTopology topology;
};

/// The volume a mesh encloses, by the divergence theorem over its faces (cubic metres):
/// positive when a closed mesh's faces wind counter-clockwise seen from outside, negative when
/// it is inside out; meaningless for an open mesh. O(T).
double signed_volume(const TriangleMesh& mesh);

/// Evaluates `mesh` against `reference`. A reference without triangles is a point set:
/// mesh -> reference distances go to the nearest point (kd-tree) and normals come from the
/// reference's normals when it has them; otherwise distances go to the nearest surface point
/// (exact) and normals are face normals. reference -> mesh distances are always to the mesh
/// surface. Throws meshflow::Error for an empty mesh or reference, or non-finite vertices.
/// Parallel over samples, deterministic; O((V + R) log) for typical inputs.
SurfaceEvaluation evaluate_surface(const TriangleMesh& mesh, const TriangleMesh& reference);

}  // namespace meshflow
