#pragma once
// Curvature-aware retriangulation (the curvature-dependent point distribution the
// reconstruction method builds on): every vertex gets a target edge length from the surface's
// curvature around it, so that the longest edge allowed (4/3 of the target) deviates from the
// surface by at most a tolerance (4/3 L = sqrt(8 tolerance / curvature)); the mesh is then
// remeshed towards those
// lengths by edge splits, collapses, flips and tangential relaxation. Flat parts end up with
// few large triangles, curved parts keep many small ones.

#include <cstddef>

#include "nodes/optimize/features.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {

struct AdaptiveRemeshConfig {
  /// Largest allowed deviation of a chord from the surface (metres); sets the target lengths.
  /// 0: six times the input's roughness (the robust spread of its free vertices about their
  /// neighbours' mean, along the normal: noise, not curvature), at least 0.01 and at most a
  /// quarter of its median edge length: a noisy scan is remeshed within its noise, a clean
  /// extraction (a CAD-like part's curved faces, exact to 1e-5 of its diagonal) within its own
  /// accuracy, so its curved parts keep their edge lengths and only flat parts grow.
  float tolerance = 0.0f;
  /// Target lengths are clamped to [min_edge, max_edge] (metres). 0: the input's median edge
  /// length (the input carries no detail finer than its own sampling), and eight times it.
  float min_edge = 0.0f;
  float max_edge = 0.0f;
  /// Curvature comes from a least-squares quadric fitted to the vertices within this many
  /// edges (2: robust to the staircase noise of marching cubes, still local).
  int curvature_rings = 2;
  /// Targets grow by at most this much per metre of distance (a smooth size transition).
  float gradation = 0.5f;
  /// Rounds of split, collapse, flip and relaxation.
  int iterations = 5;
  /// No collapse, flip or relaxation may turn a face by more than this.
  float max_normal_turn_deg = 20.0f;
  /// A border vertex is removed only where its two border edges turn by less than this.
  float max_border_turn_deg = 10.0f;
  /// Sharp edges (detect_features() with this angle, degrees; 180: none) are kept: they are
  /// split at their midpoints and collapsed only along themselves, never flipped; a vertex on a
  /// feature line is removed only where the line turns by less than max_border_turn_deg, and
  /// corners never are; feature vertices do not relax; curvature is fitted on one side of them.
  /// Before remeshing, feature vertices move onto the planes of their sides
  /// (snap_feature_vertices(): up to 2 median edge lengths, sides flat within 0.05 of one).
  float feature_angle_deg = kDefaultFeatureAngleDeg;
  /// Feature lines shorter than this are noise (metres; detect_features(): 0 = from the mesh).
  float feature_min_length = 0.0f;
};

struct AdaptiveRemeshReport {
  std::size_t vertices_in = 0, vertices_out = 0;
  std::size_t splits = 0, collapses = 0, flips = 0;
  std::size_t sharp_edges_in = 0, corners = 0;  ///< the input's feature graph
  std::size_t snapped = 0;  ///< feature vertices moved onto their sides' planes first
  float tolerance = 0.0f;   ///< the one used (metres)
  float min_target = 0.0f, max_target = 0.0f;  ///< range of the vertices' target lengths
};

/// Remeshes `mesh` (a 2-manifold; throws meshflow::Error otherwise, as HalfEdgeMesh does)
/// towards curvature-dependent edge lengths. Edges longer than 4/3 of their target are split
/// at their midpoints, shorter than 4/5 collapsed into the end with the higher curvature when
/// no new edge gets too long, no face turns by more than max_normal_turn_deg and the removed
/// vertex stays within the tolerance of the new faces; edges are flipped towards valence 6
/// where the two faces are nearly coplanar; interior vertices relax towards their neighbours'
/// centroid within their tangent plane, by no more than the curvature allows. Borders keep
/// their shape. Colours follow their vertices (new vertices: the edge's mean); normals are
/// dropped (the caller recomputes them). Curvature and relaxation are parallel over
/// vertices, the topological edits serial; deterministic. O(iterations x (V + F) x valence).
/// `features`: the feature graph of `mesh` when the caller has it (detect_features() with the
/// config's angle and length, or carried from an earlier step on the same topology); null:
/// detected here.
TriangleMesh adaptive_remesh(const TriangleMesh& mesh, const AdaptiveRemeshConfig& config = {},
                             AdaptiveRemeshReport* report = nullptr,
                             const MeshFeatures* features = nullptr);

}  // namespace meshflow
