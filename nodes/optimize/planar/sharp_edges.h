#pragma once
// Sharp edges where planar regions meet (the reconstruction thesis's plane intersection):
// marching cubes bevels every crease of a planar scene by up to a voxel; this step moves the
// vertices of the bevel between two large regions onto the nearer of the two planes (or onto
// their intersection line) and cuts the bevel's faces along that line, so the mesh follows the
// crease exactly.

#include <cstddef>

#include "nodes/optimize/planar/planar_regions.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {

struct SharpEdgeConfig {
  /// Two regions form a crease when their normals differ by more than this: |n_a . n_b| below
  /// it (0.8: 37 degrees). Flatter pairs are left to the planes step.
  float max_normal_cos = 0.8f;
  /// A region's face counts as lying in its plane when its normal is within this cosine of
  /// the plane's normal (0.9: 26 degrees); other faces of the region are treated as bevel.
  float min_face_cos = 0.9f;
  /// Regions with fewer faces take no part (small regions are clutter or noise).
  std::size_t min_region_faces = 50;
  /// Nor do regions narrower than this (metres; the width of a strip with the same spread
  /// across its main direction): the bevels themselves can form long thin regions.
  /// 0: four times the mesh's median edge length.
  float min_region_width = 0.0f;
  /// How far, in edges, the bevel between two regions may reach: vertices up to this many
  /// edges from a region's faces may be moved onto its plane. Marching cubes' bevels are one to
  /// two face rows wide.
  int rings = 3;
  /// No vertex moves farther than this (metres); 0: twice the mesh's median edge length.
  float max_move = 0.0f;
  /// A cut closer than this share of an edge's length to one of its ends moves that end onto
  /// the line instead of splitting the edge (no slivers).
  float snap_fraction = 0.15f;
};

struct SharpEdgeReport {
  std::size_t creases = 0;         ///< region pairs whose intersection line received vertices
  std::size_t to_plane = 0;        ///< bevel vertices moved onto one plane
  std::size_t to_line = 0;         ///< vertices moved onto an intersection line (snaps included)
  std::size_t to_corner = 0;       ///< vertices moved onto the meeting point of three planes
  std::size_t split_edges = 0;     ///< edges cut where they cross a line (new vertices)
  std::size_t flipped_faces = 0;   ///< faces whose normal turned by more than 90 degrees
  float max_line_distance = 0.0f;  ///< of the vertices put on lines, from their line (metres)
};

/// Sharpens the creases between the large regions of `segmentation` (computed on `mesh`).
/// Vertices within `rings` edges of two or three crease-forming regions move to the nearest
/// point of the regions' piecewise planar surface (a plane on its region's side of the crease,
/// the intersection line, or the corner of three planes) when that is within max_move; every
/// edge joining a vertex on one plane to a vertex on the other is then cut at the intersection
/// line. Faces stay oriented; a move that would turn a face by more than 90 degrees is undone.
/// Colours of new vertices are their edge's mean, normals are dropped (the caller recomputes
/// them). Requires a 2-manifold (throws meshflow::Error otherwise, as HalfEdgeMesh does).
/// Candidate search parallel over vertices, cutting serial; deterministic. O(V + F).
TriangleMesh sharpen_creases(const TriangleMesh& mesh, const PlanarSegmentation& segmentation,
                             const SharpEdgeConfig& config = {}, SharpEdgeReport* report = nullptr);

}  // namespace meshflow
