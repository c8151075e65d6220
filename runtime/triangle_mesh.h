#pragma once
// TriangleMesh: an indexed triangle mesh in metres.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "runtime/point_cloud.h"

namespace meshflow {

struct VertexTriangles;  // runtime/vertex_triangles.h

using Triangle = std::array<std::uint32_t, 3>;

/// Indexed triangles; counter-clockwise winding seen from outside (the normal side).
/// `normals` and `colors` are per vertex and either empty or as long as `vertices`.
struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<Triangle> triangles;
  std::vector<Eigen::Vector3f> normals;
  std::vector<Rgb8> colors;

  /// Whether the mesh has no triangles.
  bool empty() const { return triangles.empty(); }
};

/// Unit face normal of triangle t (zero for a degenerate triangle).
Eigen::Vector3f face_normal(const TriangleMesh& mesh, const Triangle& t);

/// Whether triangle (a, b, c) has an area float arithmetic sees from every corner: its edges'
/// cross product is non-zero at each corner and at least 1e-6 of its longest edge squared (no
/// needle or sliver flatter than a millionth of its length). Mesh edits use it to refuse faces
/// that later steps would count as degenerate. O(1).
bool has_area(const Eigen::Vector3f& a, const Eigen::Vector3f& b, const Eigen::Vector3f& c);

/// Recomputes `normals` as area-weighted averages of the adjacent face normals (unit length;
/// zero for a vertex without area around it). Parallel over vertex ranges (one per worker, each
/// scanning all triangles); every vertex sums its faces in triangle order, so the result is
/// bit-identical for any thread count. O(V + T x workers) reads, O(T) arithmetic.
/// Implemented in runtime/vertex_normals.cpp.
void compute_vertex_normals(TriangleMesh& mesh);

/// Edge incidence counts of a mesh, for validity checks and `meshflow info`.
struct EdgeStatistics {
  std::size_t edges = 0;               ///< distinct undirected edges
  std::size_t boundary_edges = 0;      ///< edges with one adjacent face
  std::size_t non_manifold_edges = 0;  ///< edges with three or more adjacent faces
  std::size_t inconsistent_edges = 0;  ///< two faces traversing the edge in the same direction
  /// No boundary and no non-manifold edge.
  bool closed() const { return boundary_edges == 0 && non_manifold_edges == 0; }
};

/// Counts edges by incidence. O(T log T) (sorts the 3T directed edges).
EdgeStatistics edge_statistics(const TriangleMesh& mesh);

/// The key of the undirected edge {a, b}: the smaller vertex in the high half, the larger in the
/// low half, so both directions give one key and keys sort by their smaller vertex. O(1).
inline std::uint64_t undirected_edge_key(std::uint32_t a, std::uint32_t b) {
  return std::uint64_t{a < b ? a : b} << 32 | (a < b ? b : a);
}

/// An edge used by one triangle only, directed as that triangle traverses it (a -> b).
struct BorderEdge {
  std::uint32_t a, b, triangle;
};

/// The border edges of a mesh, in triangle order (then edge order within the triangle).
/// Parallel over vertices; deterministic. O(V + T) time, plus O(V) memory per worker thread.
std::vector<BorderEdge> border_edges(const TriangleMesh& mesh);
/// The same with the mesh's incidence already built (vertex_triangles(mesh)).
std::vector<BorderEdge> border_edges(const TriangleMesh& mesh, const VertexTriangles& around);

/// The median length of the triangles' edges (each interior edge counted twice), metres;
/// 0 for no triangles. O(T).
float median_edge_length(const TriangleMesh& mesh);

/// What remove_small_components() counted.
struct ComponentCounts {
  std::size_t components = 0;          ///< components (by shared vertices) before removal
  std::size_t removed_components = 0;  ///< of them, those with fewer triangles than the limit
  std::size_t removed_triangles = 0;   ///< their triangles
};

/// Drops the triangles of connected components (triangles joined by shared vertices) with fewer
/// than `min_triangles` triangles, keeping the others in order (min_triangles 0: keeps all, only
/// counts); corners index `vertex_count` vertices. The one component filter of meshflow: the
/// clean step and the per-frame triangulations both use it. Adds to `counts` when given.
/// `held` (optional, one byte per vertex): a component with a vertex whose byte is non-zero is
/// kept whatever its size (a piece of a chunk that goes on across a seam). The components are
/// labelled in parallel (runtime/mesh_components.h: the same labels for any thread count), the
/// counting and the erase are serial; deterministic; O(V + T).
void remove_small_components(std::vector<Triangle>& triangles, std::size_t vertex_count,
                             std::size_t min_triangles, ComponentCounts* counts = nullptr,
                             const std::vector<std::uint8_t>* held = nullptr);

/// Throws Error(source, "face F", "vertex index I out of range (N vertices)") for the first
/// corner of `triangles` that is not below `vertex_count`. O(T).
void require_corners_in_range(const std::vector<Triangle>& triangles, std::size_t vertex_count,
                              const std::string& source);

/// A mesh of `triangles` (indices into source.vertices) that keeps only the referenced vertices,
/// in their original order, with their normals and colours; triangles are renumbered, their
/// order kept. `original` (optional) receives the source index of each kept vertex (ascending).
/// O(V + T), parallel; the result does not depend on the thread count.
TriangleMesh compact_vertices(const TriangleMesh& source, const std::vector<Triangle>& triangles,
                              std::vector<std::uint32_t>* original = nullptr);

/// Renumbers the corners of `triangles` (indices below `vertex_count`) in place to 0 .. U-1, the
/// U used vertices in their original order, and returns the original index of each (ascending).
/// Lets per-vertex passes run over the used vertices only (a quadtree frame uses a tenth of its
/// pixels). Parallel; deterministic; O(vertex_count + T), a byte and an index per vertex_count.
std::vector<std::uint32_t> renumber_used_vertices(std::vector<Triangle>& triangles,
                                                  std::size_t vertex_count);

}  // namespace meshflow
