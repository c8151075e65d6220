#pragma once
// Vertex colours of an extracted mesh from the coloured points it was made of, so that a
// coloured scan (a Kinect PCD, a coloured PLY or text cloud) gives a coloured mesh.

#include <Eigen/Core>
#include <vector>

#include "nodes/normals/spatial_index.h"
#include "runtime/point_cloud.h"

namespace meshflow {

/// The colour of each of `vertices` (metres, the cloud's frame): the average of the colours of
/// its k nearest points of `cloud` (which must have colours; `index` built over its positions),
/// weighted by the inverse of their distance (a point on the vertex: its own colour), rounded.
/// k = 4 averages sensor noise without blurring edges between colours by more than a point
/// spacing. Parallel over vertices, deterministic; O(V k log n).
std::vector<Rgb8> vertex_colors(const std::vector<Eigen::Vector3f>& vertices,
                                const PointCloud& cloud, const SpatialIndex& index, int k = 4);

}  // namespace meshflow
