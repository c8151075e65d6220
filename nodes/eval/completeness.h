#pragma once
// Completeness of a per-frame mesh against a reference mesh of the same camera frame (the
// metrics of the depth-map triangulation work the method builds on): one ray per pixel, and
// which of the two meshes each ray hits.

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "runtime/depth_frame.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {

/// Per pixel (row-major, intrinsics.width x intrinsics.height): 1 when the ray through the
/// point (u + 0.3, v + 0.6) of the image plane hits a triangle of `mesh` (world frame, seen by a
/// camera at T_world_camera). The offset keeps samples off the lines x = k, y = k and
/// x +- y = k that the edges of pixel-grid triangulations follow. Triangles behind the camera
/// are ignored. O(pixels + covered area).
std::vector<std::uint8_t> ray_coverage(const TriangleMesh& mesh,
                                       const PinholeIntrinsics& intrinsics,
                                       const Eigen::Isometry3f& T_world_camera);

struct Completeness {
  std::size_t reference_hits = 0;  ///< rays hitting the reference
  std::size_t mesh_hits = 0;       ///< rays hitting the mesh
  std::size_t shared_hits = 0;     ///< rays hitting both
  /// h_n: share of the reference's hits the mesh keeps (1 = nothing lost).
  double kept() const {
    return reference_hits ? static_cast<double>(shared_hits) / reference_hits : 1.0;
  }
  /// h_c: share of the mesh's hits the reference has too (1 = nothing invented).
  double genuine() const { return mesh_hits ? static_cast<double>(shared_hits) / mesh_hits : 1.0; }
};

/// ray_coverage of both meshes, compared pixel by pixel.
Completeness completeness(const TriangleMesh& mesh, const TriangleMesh& reference,
                          const PinholeIntrinsics& intrinsics,
                          const Eigen::Isometry3f& T_world_camera);

/// Symmetric Hausdorff distance (metres) over vertices: the larger of the farthest vertex of
/// `a` from the surface of `b` and the farthest vertex of `b` from the surface of `a` (exact
/// point-to-triangle distances). Throws meshflow::Error when either mesh has no triangle.
double hausdorff_distance(const TriangleMesh& a, const TriangleMesh& b);

}  // namespace meshflow
