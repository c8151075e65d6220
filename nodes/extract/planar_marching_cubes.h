#pragma once
// Planar marching cubes (thesis, Wiemann 2013: the PMC variant): standard marching cubes, then
// the vertices on the mesh's border are moved in the plane of their border triangles onto the
// contour of the data, so bounded planes end where the measurements end instead of a voxel or
// two beyond (or short of) it.

#include <cstdint>
#include <vector>

#include "nodes/extract/marching_cubes.h"
#include "nodes/search/spatial_index.h"
#include "runtime/point_cloud.h"

namespace meshflow {

struct PlanarContourConfig {
  /// Points are searched up to this many voxels from a border vertex; must exceed how far the
  /// marching-cubes border can lie from the data (about DistanceConfig::max_distance_voxels).
  float search_voxels = 2.5f;
  /// Half-width of the strip, along the border, whose points define the contour (voxels).
  float strip_voxels = 0.25f;
  /// A gap wider than this between consecutive points across the strip ends the data (voxels).
  float gap_voxels = 0.5f;
};

/// Moves every border vertex (on an edge used by one triangle) along its outward in-plane
/// direction (the mean of its border edges' outward directions, orthogonal to the mean normal
/// of its border triangles) to the data contour: the outermost point of the contiguous run of
/// points in a strip through the vertex across the border, found from the inner side. The
/// component along the normal (the interpolated height) is kept. Vertices without data in reach
/// stay. Border triangles left without area (three vertices on one straight contour) are
/// removed. Parallel over vertices, reads original positions only: deterministic. O(B log n).
void move_border_to_contour(TriangleMesh& mesh, const PointCloud& cloud, const SpatialIndex& index,
                            float voxel_size, const PlanarContourConfig& config = {});

/// The vertices of `mesh` (extracted from `cloud`'s field, e.g. by planar_marching_cubes) that
/// lie where the data shows a sharp feature: one byte per vertex, 1 where some point within
/// `reach_voxels` voxels of it has a normal more than `angle_deg` degrees from the nearest
/// point's (two faces of an edge, or three of a corner, are both in reach: marching cubes cut
/// the feature off there, and these vertices bound that cut, within about a voxel of it). They
/// play the part of extended marching cubes' feature vertices for the feature graph
/// (detect_features' seed: lines between two of them are never dropped as noise). Meant for
/// clean samples with per-face normals (NormalsConfig::Sharp): on a noisy scan's normals most
/// vertices pass. A cloud without normals: all 0. Parallel over vertices, deterministic;
/// O(V (log n + points in reach)).
std::vector<std::uint8_t> data_feature_vertices(const TriangleMesh& mesh, const PointCloud& cloud,
                                                const SpatialIndex& index, float voxel_size,
                                                float angle_deg = 30.0f, float reach_voxels = 1.0f);

/// marching_cubes, then move_border_to_contour (vertex normals recomputed when requested).
TriangleMesh planar_marching_cubes(const SparseGrid& grid, const DistanceField& field,
                                   const PointCloud& cloud, const SpatialIndex& index,
                                   const ExtractConfig& config = {},
                                   const PlanarContourConfig& contour = {});

}  // namespace meshflow
