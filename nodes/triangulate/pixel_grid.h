#pragma once
// The pixel grid every depth-map triangulation works on: one world point per pixel (NaN where
// the pixel is invalid), the camera position, and the helpers the triangulations share (the
// occlusion test of a triangle, compaction of pixel-index triangles into a mesh).

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "nodes/depth/depth_filter.h"
#include "runtime/depth_frame.h"
#include "runtime/point_cloud.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {

struct PointGrid {
  int width = 0, height = 0;
  std::vector<Eigen::Vector3f> points;            ///< row-major, world frame, metres; NaN = invalid
  Eigen::Vector3f eye = Eigen::Vector3f::Zero();  ///< camera centre, world frame
  /// Per pixel, row-major, when the input has them (an organized cloud's); else empty. The
  /// mesh's vertices keep them (mesh_from_pixel_triangles).
  std::vector<Rgb8> colors;
  std::vector<Eigen::Vector3f> normals;
  /// Whether point i was measured (not NaN).
  bool valid(std::size_t i) const { return !std::isnan(points[i].x()); }
  /// Index of pixel (u, v): column u, row v.
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
/// origin when unset), with the cloud's colours and normals; the range limits and occlusion
/// edges of `filter` apply to the range from it. Throws meshflow::Error for an unorganized cloud or
/// a non-finite sensor origin. O(pixels).
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
  /// The test with these limits (degrees; longest over shortest edge).
  OcclusionTriangleTest(float max_view_angle_deg, float max_edge_ratio);
  enum Verdict { kKeep, kViewAngle, kShape };
  /// Whether triangle p0 p1 p2 (metres) seen from `eye` is kept, or why not. Thread-safe; O(1).
  Verdict operator()(const Eigen::Vector3f& p0, const Eigen::Vector3f& p1,
                     const Eigen::Vector3f& p2, const Eigen::Vector3f& eye) const;
  /// The test itself, on the corners' coordinates (x, y, z of p0, then p1, then p2), without
  /// branches so that a loop over triangles vectorises (filter()). Thread-safe; O(1).
  static Verdict verdict(const float corners[9], const float eye[3], float min_cos_view_squared,
                         float max_ratio_squared);
  /// Removes from triangles [first, end) (corners: pixel indices of valid pixels of `grid`) the
  /// ones operator() rejects, keeping the others in order; adds the rejections to `rejected`
  /// when given. The same verdicts as operator(), computed in batches without branches (the
  /// loop vectorises). Thread-safe for distinct vectors; O(end - first).
  void filter(const PointGrid& grid, std::vector<Triangle>& triangles, std::size_t first,
              OcclusionRejections* rejected = nullptr) const;

 private:
  float min_cos_view_squared_, max_ratio_squared_;
};

// Inline: called once per candidate triangle of every frame, in a vectorised loop.
inline OcclusionTriangleTest::Verdict OcclusionTriangleTest::verdict(const float c[9],
                                                                     const float eye[3],
                                                                     float min_cos_view_squared,
                                                                     float max_ratio_squared) {
  const float e01x = c[3] - c[0], e01y = c[4] - c[1], e01z = c[5] - c[2];
  const float e02x = c[6] - c[0], e02y = c[7] - c[1], e02z = c[8] - c[2];
  const float e12x = c[6] - c[3], e12y = c[7] - c[4], e12z = c[8] - c[5];
  // Seen edge-on: |n . r| < cos(max angle) |n| |r| for the normal n and the ray r to the
  // centroid, compared squared (no square roots).
  const float nx = e01y * e02z - e01z * e02y, ny = e01z * e02x - e01x * e02z,
              nz = e01x * e02y - e01y * e02x;
  const float rx = (c[0] + c[3] + c[6]) / 3.0f - eye[0];
  const float ry = (c[1] + c[4] + c[7]) / 3.0f - eye[1];
  const float rz = (c[2] + c[5] + c[8]) / 3.0f - eye[2];
  const float dot = nx * rx + ny * ry + nz * rz;
  const float n2 = nx * nx + ny * ny + nz * nz, r2 = rx * rx + ry * ry + rz * rz;
  const int view_ok = dot * dot >= min_cos_view_squared * n2 * r2;
  // Shape: the longest edge over the ratio times the shortest, compared squared.
  const float e0 = e01x * e01x + e01y * e01y + e01z * e01z;
  const float e1 = e12x * e12x + e12y * e12y + e12z * e12z;
  const float e2 = e02x * e02x + e02y * e02y + e02z * e02z;
  const float longest = std::max(std::max(e0, e1), e2), shortest = std::min(std::min(e0, e1), e2);
  const int shape_ok = longest <= max_ratio_squared * shortest;
  return static_cast<Verdict>((1 - view_ok) * kViewAngle + view_ok * (1 - shape_ok) * kShape);
}

inline OcclusionTriangleTest::Verdict OcclusionTriangleTest::operator()(
    const Eigen::Vector3f& p0, const Eigen::Vector3f& p1, const Eigen::Vector3f& p2,
    const Eigen::Vector3f& eye) const {
  const float corners[9] = {p0.x(), p0.y(), p0.z(), p1.x(), p1.y(), p1.z(), p2.x(), p2.y(), p2.z()};
  const float at[3] = {eye.x(), eye.y(), eye.z()};
  return verdict(corners, at, min_cos_view_squared_, max_ratio_squared_);
}

/// The mesh whose vertex i is pixel `pixels[i]` of `grid` (position, and the grid's colour and
/// normal when it has them), with `triangles` indexing those vertices (moved in: pass an rvalue
/// to avoid a copy). Parallel over vertices; deterministic; O(vertices + triangles).
TriangleMesh mesh_from_grid_pixels(const PointGrid& grid, const std::vector<std::uint32_t>& pixels,
                                   std::vector<Triangle> triangles);

/// The mesh of `pixel_triangles` (corners are pixel indices of `grid`): vertices are the used
/// pixels in row-major order (renumber_used_vertices), with the grid's colours and normals when
/// it has them. Parallel; deterministic; O(pixels + triangles).
TriangleMesh mesh_from_pixel_triangles(const PointGrid& grid,
                                       std::vector<Triangle> pixel_triangles);

}  // namespace meshflow
