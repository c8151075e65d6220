#pragma once
// Marching cubes over a sparse grid with shared vertices (one per crossed grid edge).

#include "runtime/distance_field.h"
#include "runtime/sparse_grid.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {

/// Extraction methods of the `extract` stage (thesis, Wiemann 2013, compares them on one grid).
enum class ExtractMethod {
  /// The pipeline's extract stage picks kExtendedMarchingCubes for clean samples without a
  /// sensor (when the normals stage estimated sharp-feature normals: NormalsConfig::Sharp)
  /// and kMarchingCubes otherwise; extract_surface() alone treats it as kMarchingCubes.
  kAuto,
  kMarchingCubes,         ///< marching_cubes
  kMarchingTetrahedra,    ///< marching_tetrahedra: six tetrahedra per cell, no ambiguities
  kPlanarMarchingCubes,   ///< planar_marching_cubes: border moved onto the data contour
  kExtendedMarchingCubes  ///< extended_marching_cubes: sharp edges and corners kept
};

struct ExtractConfig {
  float iso = 0.0f;            ///< iso-value of the surface (metres of signed distance)
  bool vertex_normals = true;  ///< compute area-weighted vertex normals
  ExtractMethod method = ExtractMethod::kAuto;  ///< used by extract_surface
  /// Extended marching cubes leaves its edge-flip pass (flip_edges_between_features) to the
  /// caller and extract_surface() reports the feature vertices: the out-of-core path flips
  /// once its chunks are stitched, where a seam's two sides are one mesh.
  bool defer_feature_flips = false;
};

/// Extracts the iso-surface of `field` over every cell of `grid` whose 8 corners are valid.
/// Vertices are shared between cells (one per crossed edge, numbered in edge order): no duplicate
/// vertices and no cracks; triangles wind counter-clockwise seen from the positive side, so
/// face normals point where the field grows. Interpolation parameters are clamped to
/// [1e-3, 1 - 1e-3] so no two vertices coincide. Parallel and deterministic; O(cells + corners).
TriangleMesh marching_cubes(const SparseGrid& grid, const DistanceField& field,
                            const ExtractConfig& config = {});

}  // namespace meshflow
