#pragma once
// Extended Marching Cubes (Kobbelt, Botsch, Schwanecke, Seidel 2001, "Feature sensitive surface
// extraction from volume data"), on point data as in the reconstruction thesis: edge crossings
// from directed distances to the points' oriented disks, a feature vertex where the tangent
// planes of a sharp cell meet, fans around it, and edge flips along the features. Plain
// marching cubes rounds a box's edges and corners off by a fraction of a voxel; EMC keeps them.

#include <cstdint>
#include <vector>

#include "nodes/extract/directed_distance.h"
#include "nodes/extract/marching_cubes.h"
#include "nodes/extract/sharp_feature.h"
#include "nodes/search/spatial_index.h"
#include "runtime/point_cloud.h"

namespace meshflow {

struct ExtendedMcConfig {
  DirectedDistanceConfig directed;
  SharpFeatureConfig feature;
  bool flip_edges = true;  ///< run the edge-flip pass
};

/// Per active cell, per marching-cubes contour loop: the loop's edge crossings come from
/// directed_edge_hit (with the disk normals); when sharp_feature finds an edge or a corner the
/// loop is filled by a fan around the feature vertex, otherwise by marching cubes' triangles.
/// Then flip_edges_between_features. `cloud` needs normals and `index` must be built over
/// cloud.positions. Closed, consistently oriented output on closed input (as marching_cubes);
/// edge vertices first (edge order), then feature vertices in cell order. Parallel and
/// deterministic; O(cells + crossings (log n + neighbours)). `feature_vertices` (optional)
/// receives one byte per output vertex, 1 for the feature vertices (what the flip pass takes).
TriangleMesh extended_marching_cubes(const SparseGrid& grid, const DistanceField& field,
                                     const PointCloud& cloud, const SpatialIndex& index,
                                     const ExtractConfig& config = {},
                                     const ExtendedMcConfig& emc = {},
                                     std::vector<std::uint8_t>* feature_vertices = nullptr);

}  // namespace meshflow
