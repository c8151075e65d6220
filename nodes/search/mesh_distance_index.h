#pragma once
// Exact point-to-surface distance queries against a triangle mesh, through a uniform grid of
// triangle buckets searched in growing rings.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "runtime/triangle_mesh.h"
#include "runtime/voxel_key.h"

namespace meshflow {

class MeshDistanceIndex {
 public:
  struct Hit {
    float distance = 0.0f;       ///< metres; +inf when the mesh has no triangle
    std::uint32_t triangle = 0;  ///< nearest triangle
    Eigen::Vector3f point = Eigen::Vector3f::Zero();  ///< nearest surface point
  };

  /// Buckets every triangle into the grid cells its bounding box overlaps (cell edge: twice the
  /// mean triangle extent, at least 1/1000 of the mesh's diagonal). Keeps a reference to
  /// `mesh`, which must outlive the index. Throws meshflow::Error for non-finite vertices.
  /// O(T log T).
  explicit MeshDistanceIndex(const TriangleMesh& mesh);

  /// The nearest point of the surface to p (exact). With `enough` > 0 the search stops at the
  /// first point it finds within `enough` of p, if there is one (then not necessarily the
  /// nearest: for maxima of distances, such as a Hausdorff distance, where a point closer than
  /// the maximum so far is all a query needs to know); else it is exact. Thread-safe (const).
  /// About O(triangles in the rings searched); far-away queries search up to the whole grid.
  Hit closest(const Eigen::Vector3f& p, float enough = 0.0f) const;

 private:
  const TriangleMesh& mesh_;
  float cell_ = 1.0f;
  Eigen::Vector3i lo_ = Eigen::Vector3i::Zero(), hi_ = Eigen::Vector3i::Zero();  // cell bounds
  std::vector<VoxelKey> keys_;            // sorted cells that hold triangles
  std::vector<std::uint32_t> offsets_;    // keys_.size() + 1
  std::vector<std::uint32_t> triangles_;  // bucket contents
};

}  // namespace meshflow
