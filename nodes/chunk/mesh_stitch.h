#pragma once
// Joining chunk meshes into one: vertices that marching cubes put on the same lattice edge of
// the global grid are the same vertex, whichever chunk made them, so meshes of neighbouring
// chunks share their seam vertices and the joined mesh is manifold across seams.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "runtime/triangle_mesh.h"

namespace meshflow::chunk {

/// The key of the lattice edge (segment between two neighbouring grid corners) that `p` lies
/// on: two coordinates on grid planes (within 1e-4 voxel: interpolation rounds them by an ulp)
/// and the third at least 5e-4 voxel from any (extraction clamps the crossing to [1e-3, 1 -
/// 1e-3] of the edge); packed as the lower corner's key times 3 plus the axis. Returns
/// UINT64_MAX for a point on no lattice edge (a feature vertex inside a cell, a diagonal of
/// marching tetrahedra, a moved vertex). O(1).
std::uint64_t lattice_edge_key(const Eigen::Vector3f& p, float voxel_size);

/// Collects chunk meshes and welds them (not thread-safe; add in a fixed order for a
/// deterministic result).
class MeshStitcher {
 public:
  /// `voxel_size` of the grid every chunk mesh was extracted on, metres.
  explicit MeshStitcher(float voxel_size) : voxel_size_(voxel_size) {}

  /// Appends a chunk's mesh (vertices in the common local frame; normals and colours kept when
  /// every chunk has them) and optionally a byte per vertex (`vertex_flags`, e.g. Frame::
  /// beyond_data; kept when every chunk gives them). O(V + T).
  void add(const TriangleMesh& mesh, const std::vector<std::uint8_t>& vertex_flags = {});

  /// The joined mesh: vertices with one lattice edge key merged (the first chunk's copy kept),
  /// vertices on no lattice edge kept apart, unused vertices dropped, triangles in the order
  /// added. `merged` (optional) receives the number of seam vertices merged, `vertex_flags`
  /// (optional) the kept vertices' flags (empty unless every chunk gave them). O(V log V + T).
  TriangleMesh stitch(std::size_t* merged = nullptr,
                      std::vector<std::uint8_t>* vertex_flags = nullptr);

 private:
  float voxel_size_;
  TriangleMesh joined_;
  std::vector<std::uint64_t> keys_;
  std::vector<std::uint8_t> flags_;
  bool normals_ = true, colors_ = true, flags_given_ = true;
};

}  // namespace meshflow::chunk
