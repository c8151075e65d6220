#pragma once
// Incremental marching cubes over a TsdfVolume: each block is meshed on its own (its 8^3 cells,
// reading the face voxels of its +x / +y / +z neighbours), the per-block meshes are cached, and
// only blocks whose voxels or neighbours changed since the last extraction are meshed again.
// Vertices on grid edges shared between blocks are welded, so the mesh has no cracks.

#include <cstdint>
#include <unordered_map>
#include <vector>

#include "nodes/fusion/tsdf_volume.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {

struct TsdfExtractStats {
  std::size_t blocks_meshed = 0;  ///< re-meshed in this call
  std::size_t blocks_cached = 0;  ///< reused from an earlier call
};

class TsdfMesher {
 public:
  /// The surface distance = 0 of `volume`: a cell is meshed when its observed corners (weight
  /// > 0) lie on both sides of the surface and its corners no frame reached have no edge
  /// neighbour in the cell in front of the surface: those count as behind it (distance
  /// -truncation), since every frame's band reaches farther in front of a surface than behind.
  /// Vertex colours are interpolated from the voxels; triangles wind counter-clockwise seen from
  /// the free-space side (positive distance), vertex normals are area-weighted. Re-meshes only
  /// blocks changed since this mesher's last call (per-block work in parallel); the output is
  /// identical to a fresh mesher's and does not depend on the thread count. Not thread-safe against
  /// integration into `volume` at the same time.
  TriangleMesh extract(const TsdfVolume& volume, TsdfExtractStats* stats = nullptr);

  /// One block's piece of the surface: vertices with the global key of their grid edge.
  struct BlockMesh {
    std::vector<Eigen::Vector3f> vertices;
    std::vector<Rgb8> colors;
    std::vector<std::uint64_t> edge_keys;  ///< (pack_key(lower voxel) << 2) | axis
    std::vector<Triangle> triangles;       ///< indices into this block's vertices
  };

 private:
  // extract()'s phases: which blocks to mesh again, then their meshes (cached ones reused), in
  // the volume's key order.
  std::vector<std::uint8_t> dirty_blocks(const TsdfVolume& volume,
                                         const std::vector<std::uint32_t>& order) const;
  std::vector<const BlockMesh*> remesh(const TsdfVolume& volume,
                                       const std::vector<std::uint32_t>& order,
                                       const std::vector<std::uint8_t>& dirty,
                                       TsdfExtractStats& stats);

  std::unordered_map<VoxelKey, BlockMesh> cache_;  // by pack_key(block coords)
  std::uint64_t meshed_generation_ = 0;            // volume generation at the last call
  const TsdfVolume* volume_ = nullptr;             // the volume the cache belongs to
};

}  // namespace meshflow
