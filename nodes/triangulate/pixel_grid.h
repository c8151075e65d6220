#pragma once
// The pixel grid every depth-map triangulation works on: one world point per pixel (NaN where
// the pixel is invalid), the camera position, and the helpers the triangulations share (the
// occlusion test of a triangle, compaction of pixel-index triangles into a mesh).

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "nodes/filter/depth_filter.h"
#include "runtime/depth_frame.h"
#include "runtime/point_cloud.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {

struct PointGrid {
  int width = 0, height = 0;
  std::vector<Eigen::Vector3f> points;            ///< row-major, world frame, metres; NaN = invalid
  Eigen::Vector3f eye = Eigen::Vector3f::Zero();  ///< camera centre, world frame
  bool valid(std::size_t i) const { return !std::isnan(points[i].x()); }
  std::size_t index(int u, int v) const {
    return static_cast<std::size_t>(v) * static_cast<std::size_t>(width) +
           static_cast<std::size_t>(u);
  }
};

/// Filters the frame's depth (range, smoothing, occlusion edges: filter_depth) and back-projects
/// every valid pixel through the intrinsics and T_world_camera. Throws meshflow::Error for an
/// empty image or one whose size differs from the intrinsics. Parallel over rows; O(pixels).
PointGrid grid_from_depth(const DepthFrame& frame, const DepthFilterConfig& filter,
                          DepthFilterCounts* counts = nullptr);

/// An organized cloud (width x height, NaN = invalid) as a grid seen from its sensor origin (the
/// origin when unset); the range limits and occlusion edges of `filter` apply to the range from
/// it. Throws meshflow::Error for an unorganized cloud. O(pixels).
PointGrid grid_from_organized(const PointCloud& cloud, const DepthFilterConfig& filter,
                              DepthFilterCounts* counts = nullptr);

/// Triangles an occlusion test dropped, by reason.
struct OcclusionRejections {
  std::size_t view = 0, shape = 0;
};

/// Rejects triangles that span an occlusion: seen more edge-on than `max_view_angle_deg`, or
/// with a longest edge over `max_edge_ratio` times the shortest.
class OcclusionTriangleTest {
 public:
  OcclusionTriangleTest(float max_view_angle_deg, float max_edge_ratio);
  enum Verdict { kKeep, kViewAngle, kShape };
  Verdict operator()(const Eigen::Vector3f& p0, const Eigen::Vector3f& p1,
                     const Eigen::Vector3f& p2, const Eigen::Vector3f& eye) const;
  /// Removes from triangles [first, end) (corners: pixel indices of valid pixels of `grid`) the
  /// ones operator() rejects, keeping the others in order; adds the rejections to `rejected`
  /// when given. The same verdicts as operator(), computed in batches without branches (the
  /// loop vectorises). Thread-safe for distinct vectors; O(end - first).
  void filter(const PointGrid& grid, std::vector<Triangle>& triangles, std::size_t first,
              OcclusionRejections* rejected = nullptr) const;

 private:
  float min_cos_view_squared_, max_ratio_squared_;
};

// Inline: called once per candidate triangle of every frame.
inline OcclusionTriangleTest::Verdict OcclusionTriangleTest::operator()(
    const Eigen::Vector3f& p0, const Eigen::Vector3f& p1, const Eigen::Vector3f& p2,
    const Eigen::Vector3f& eye) const {
  const Eigen::Vector3f normal = (p1 - p0).cross(p2 - p0);
  const Eigen::Vector3f ray = (p0 + p1 + p2) / 3.0f - eye;
  // |n . r| >= cos(max angle) |n| |r|, squared (no square roots).
  const float dot = normal.dot(ray);
  if (!(dot * dot >= min_cos_view_squared_ * normal.squaredNorm() * ray.squaredNorm()))
    return kViewAngle;
  const float e0 = (p1 - p0).squaredNorm(), e1 = (p2 - p1).squaredNorm(),
              e2 = (p0 - p2).squaredNorm();
  if (!(std::max({e0, e1, e2}) <= max_ratio_squared_ * std::min({e0, e1, e2}))) return kShape;
  return kKeep;
}

/// The mesh of `pixel_triangles` (corners are pixel indices of `grid`): vertices are the used
/// pixels in row-major order; the triangles are renumbered in place (pass an rvalue to avoid a
/// copy). Parallel over rows; deterministic; O(pixels + triangles).
TriangleMesh mesh_from_pixel_triangles(const PointGrid& grid,
                                       std::vector<Triangle> pixel_triangles);

}  // namespace meshflow
