#pragma once
// Statistics of one mesh on its own (no reference): size, area, enclosed volume, topology
// (Euler characteristic, genus, components, border loops, manifoldness) and bounds. What
// `meshflow info MESH` prints; the topology counts are mesh_topology()'s, shared with eval.

#include <Eigen/Geometry>
#include <cstddef>
#include <optional>

#include "nodes/eval/surface_eval.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {

struct MeshStatistics {
  std::size_t vertices = 0;             ///< all vertices of the file
  std::size_t referenced_vertices = 0;  ///< vertices some triangle uses
  std::size_t triangles = 0;
  MeshTopology topology;                  ///< edges, border loops, degenerate faces
  std::size_t components = 0;             ///< triangles joined by shared vertices
  std::size_t non_manifold_vertices = 0;  ///< vertices whose triangles form more than one fan
  double area = 0.0;                      ///< m^2, sum of the triangles' areas
  /// Whether every edge has two faces traversing it in opposite directions (watertight and
  /// consistently oriented): only then is the volume meaningful.
  bool closed = false;
  /// Enclosed volume, m^3, when closed: positive when the faces wind counter-clockwise seen
  /// from outside, negative when the mesh is inside out.
  std::optional<double> volume;
  /// Euler characteristic V - E + F over referenced vertices.
  long long euler_characteristic = 0;
  /// Total genus (handles summed over components) of an oriented 2-manifold mesh (no
  /// non-manifold edge or vertex, no inconsistent edge), from
  /// V - E + F = 2 C - 2 g - B (C components, B border loops); nullopt otherwise.
  std::optional<long long> genus;
  /// Box of the referenced vertices (empty for a mesh without triangles).
  Eigen::AlignedBox3f bounds;
};

/// Statistics of `mesh`, whose corners must index its vertices (require_corners_in_range()).
/// Deterministic. O(T log T) (the edge sort of mesh_topology), O(V + T) memory.
MeshStatistics mesh_statistics(const TriangleMesh& mesh);

}  // namespace meshflow
