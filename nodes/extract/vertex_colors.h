#pragma once
// Vertex colours of an extracted mesh from the coloured points it was made of, so that a
// coloured scan (a Kinect PCD, a coloured PLY or text cloud) gives a coloured mesh.

#include <Eigen/Core>
#include <vector>

#include "nodes/search/spatial_index.h"
#include "runtime/depth_frame.h"
#include "runtime/point_cloud.h"

namespace meshflow {

/// The colour of each of `vertices` (metres, the cloud's frame): the average of the colours of
/// its k nearest points of `cloud` (which must have colours; `index` built over its positions),
/// weighted by the inverse of their distance (a point on the vertex: its own colour), rounded.
/// k = 4 averages sensor noise without blurring edges between colours by more than a point
/// spacing. Parallel over vertices, deterministic; O(V k log n).
std::vector<Rgb8> vertex_colors(const std::vector<Eigen::Vector3f>& vertices,
                                const PointCloud& cloud, const SpatialIndex& index, int k = 4);

/// The colour of each of `vertices` (metres, world frame) from `frame`'s colour image (RGB8,
/// RGB, the depth image's size): the vertex projected through the frame's pose and intrinsics,
/// bilinear between the 4 nearest pixels, clamped to the image (a vertex projecting outside it
/// takes the border's colour, one behind the camera the centre's). Empty when the frame has no
/// colour image of the intrinsics' size.
/// Parallel over vertices, deterministic; O(V).
std::vector<Rgb8> vertex_colors_from_image(const std::vector<Eigen::Vector3f>& vertices,
                                           const DepthFrame& frame);

}  // namespace meshflow
