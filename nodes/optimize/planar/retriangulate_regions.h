#pragma once
// Contours and retriangulation of planar regions (the reconstruction thesis's optimisation
// stage): each region's outer and inner contours are simplified with Douglas-Peucker and the
// region is triangulated anew from its contour vertices alone (constrained Delaunay
// triangulation of a polygon with holes, CGAL), so a flat wall of thousands of marching-cubes
// triangles becomes a handful while staying joined to everything around it.

#include <cstddef>

#include "nodes/optimize/features.h"
#include "nodes/optimize/planar/planar_regions.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {

struct RetriangulationConfig {
  /// Douglas-Peucker tolerance, metres: a contour vertex is dropped only when it lies within
  /// this distance of the simplified contour (0: only vertices exactly on a straight run).
  float contour_tolerance = 0.02f;
  /// Corners of the feature graph (detect_features() with this angle, degrees, and
  /// feature_min_length metres: 0 = from the mesh) stay on the contours: the ends of a sharp
  /// edge, and where one bends, are not simplified away. 180: no features.
  float feature_angle_deg = kDefaultFeatureAngleDeg;
  float feature_min_length = 0.0f;
};

struct RetriangulationReport {
  std::size_t regions = 0;
  std::size_t retriangulated = 0;            ///< regions replaced by a new triangulation
  std::size_t kept = 0;                      ///< regions left as they were (see the function)
  std::size_t contour_vertices = 0;          ///< on the contours of retriangulated regions, before
  std::size_t dropped_contour_vertices = 0;  ///< removed by Douglas-Peucker
  std::size_t removed_faces = 0, added_faces = 0;
  /// The largest distance of a dropped contour vertex from its simplified contour (metres).
  double max_contour_deviation = 0.0;
};

/// Replaces the faces of every region of `segmentation` by a triangulation of its contours.
/// Contours are split into chains at fixed vertices (those touching a face outside every
/// region, three or more regions, or the mesh border and two regions, and the feature graph's
/// corners); each chain, shared by
/// the two regions on its sides or lying on the mesh border, is simplified once with
/// Douglas-Peucker, so neighbours keep sharing their boundary and the mesh stays connected.
/// Where a region touches itself at a vertex, its faces around that vertex are left out of it
/// (they stay as they are) until every contour vertex lies on one loop; so are its faces around
/// contour vertices off its plane (farther than twice its 95th-percentile deviation and than
/// contour_tolerance / 20; a ring per round, up to four), which would tilt its new triangles.
/// Regions are triangulated in their plane (vertices keep their 3D positions); a region whose
/// projection folds or whose simplified contour would cross itself is kept as it was, with its
/// contours unsimplified. Vertices no longer used (region interiors, dropped contour vertices) are
/// removed; normals and colours follow the rest. Regions are processed in parallel; deterministic.
/// O(F + sum over regions of c log c). `segmentation` must come from grow_planar_regions on
/// HalfEdgeMesh(mesh) (face f of the half-edge mesh is mesh.triangles[f]). `features`: the feature
/// graph of `mesh` when the caller has it (detect_features() with config's angle and length, or
/// one carried from an earlier step on the same topology); null: detected here. Throws
/// meshflow::Error for non-manifold input.
TriangleMesh retriangulate_regions(const TriangleMesh& mesh, const PlanarSegmentation& segmentation,
                                   const RetriangulationConfig& config = {},
                                   RetriangulationReport* report = nullptr,
                                   const MeshFeatures* features = nullptr);

}  // namespace meshflow
