#pragma once
// Per-frame triangulation of depth maps (the depth-map triangulation work the method builds on):
// pre-processing removes invalid and out-of-range pixels and occlusion edges (depth jumps, with
// hysteresis so edges are continuous); the naive triangulation then makes two triangles per
// valid 2 x 2 pixel quad, sharing one vertex per pixel, and drops triangles whose viewing angle
// or shape marks them as spanning an occlusion the edge mask missed.

#include <cstddef>

#include "nodes/filter/depth_filter.h"
#include "runtime/depth_frame.h"
#include "runtime/point_cloud.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {

struct DepthTriangulationConfig {
  DepthFilterConfig filter;  ///< range limits, smoothing, occlusion edges (hysteresis)
  /// A triangle whose normal is more than this many degrees from the viewing ray is seen
  /// edge-on: it spans a depth jump, not a surface.
  float max_view_angle_deg = 84.0f;
  /// A triangle whose longest edge exceeds this many times its shortest is a sliver across a
  /// jump.
  float max_edge_ratio = 8.0f;
};

struct TriangulationCounts {
  DepthFilterCounts filter;        ///< pre-processing (depth frames; edges also for clouds)
  std::size_t quads = 0;           ///< 2 x 2 pixel quads with at least three valid pixels
  std::size_t rejected_view = 0;   ///< triangles dropped for their viewing angle
  std::size_t rejected_shape = 0;  ///< triangles dropped for their edge ratio
};

/// Triangulates a depth frame in the world frame (T_world_camera; metres). Triangles wind
/// counter-clockwise seen from the camera; each quad is split along its shorter 3D diagonal;
/// vertices are the used pixels in row-major order. Parallel over rows, deterministic;
/// O(pixels). Throws meshflow::Error for an empty or mis-sized image.
TriangleMesh triangulate_depth(const DepthFrame& frame, const DepthTriangulationConfig& config = {},
                               TriangulationCounts* counts = nullptr);

/// The same for an organized cloud (width x height points, NaN = invalid), e.g. a Kinect PCD:
/// occlusion edges are found on the range from `cloud.sensor_origin` (the origin when unset),
/// and range limits apply to that range. Throws meshflow::Error for an unorganized cloud.
TriangleMesh triangulate_organized(const PointCloud& cloud,
                                   const DepthTriangulationConfig& config = {},
                                   TriangulationCounts* counts = nullptr);

}  // namespace meshflow
