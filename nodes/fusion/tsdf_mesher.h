#pragma once
// Incremental marching cubes over a TsdfMap: each block is meshed on its own (its 8^3 cells,
// reading the face voxels of its +x / +y / +z neighbours), the per-block meshes are cached, and
// only blocks whose voxels or neighbours changed since the last extraction are meshed again.
// Vertices on grid edges shared between blocks are welded, so the mesh has no cracks.

#include <cstdint>
#include <unordered_map>
#include <vector>

#include "nodes/fusion/tsdf_map.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {

/// Where the map's surface goes at extraction, per cell (8 voxels) and voxel of all blocks.
struct TsdfCellCounts {
  std::size_t voxels_observed = 0;      ///< weight above the mesher's minimum
  std::size_t voxels_below_weight = 0;  ///< observed, but at or below the minimum weight
  std::size_t cells_meshed = 0;         ///< with a piece of the surface
  std::size_t cells_completed = 0;  ///< of which had unobserved corners counted behind the surface
  /// A surface between observed corners, left out: an unobserved corner beside free space (the
  /// edge of a view) — the holes of the map.
  std::size_t cells_left_out = 0;
  /// Adds another count.
  TsdfCellCounts& operator+=(const TsdfCellCounts& o);
};

struct TsdfExtractStats {
  std::size_t blocks_meshed = 0;  ///< re-meshed in this call
  std::size_t blocks_cached = 0;  ///< reused from an earlier call
  TsdfCellCounts cells;           ///< over every block of the map
};

class TsdfMesher {
 public:
  /// Voxels whose accumulated weight is at most `min_weight` count as unobserved (0: every
  /// observed voxel is used; e.g. 2 keeps only surface seen in at least three frames with the
  /// constant weighting). Throws meshflow::Error for a negative or non-finite value.
  explicit TsdfMesher(float min_weight = 0.0f);

  /// The surface distance = 0 of `volume`: a cell is meshed when its observed corners (weight
  /// > the minimum) lie on both sides of the surface and its corners no frame reached have no edge
  /// neighbour in the cell in front of the surface: those count as behind it (distance
  /// -truncation), since every frame's band reaches farther in front of a surface than behind.
  /// Vertex colours are interpolated from the voxels; triangles wind counter-clockwise seen from
  /// the free-space side (positive distance), vertex normals are area-weighted. Re-meshes only
  /// blocks changed since this mesher's last call (per-block work in parallel); the output is
  /// identical to a fresh mesher's and does not depend on the thread count. Not thread-safe against
  /// integration into `volume` at the same time.
  TriangleMesh extract(const TsdfMap& volume, TsdfExtractStats* stats = nullptr);

  /// One block's piece of the surface: vertices with the global key of their grid edge.
  struct BlockMesh {
    std::vector<Eigen::Vector3f> vertices;
    std::vector<Rgb8> colors;
    std::vector<std::uint64_t> edge_keys;  ///< (pack_key(lower voxel) << 2) | axis
    std::vector<Triangle> triangles;       ///< indices into this block's vertices
    TsdfCellCounts counts;                 ///< this block's cells and voxels
  };

  /// The blocks' meshes brought up to date as extract() does (only changed blocks re-meshed),
  /// without joining them: returns pack_key(block coords) of every block whose piece of the
  /// surface (vertices, colours, triangles) differs from what this mesher held before (a block
  /// new to the mesher counts when its piece is not empty), in the volume's key order. For
  /// sending a growing map's changes (serve/map_publisher.h). Same thread-safety as extract().
  std::vector<VoxelKey> update(const TsdfMap& volume, TsdfExtractStats* stats = nullptr);
  /// The piece of block `key` (pack_key of its coordinates) as of the last update() or
  /// extract(), or nullptr. Valid until the next call of either.
  const BlockMesh* block_mesh(VoxelKey key) const;

 private:
  // extract()'s phases: which blocks to mesh again, then their meshes (cached ones reused), in
  // the volume's key order.
  std::vector<std::uint8_t> dirty_blocks(const TsdfMap& volume,
                                         const std::vector<std::uint32_t>& order) const;
  std::vector<const BlockMesh*> remesh(const TsdfMap& volume,
                                       const std::vector<std::uint32_t>& order,
                                       const std::vector<std::uint8_t>& dirty,
                                       TsdfExtractStats& stats,
                                       std::vector<std::uint8_t>* changed = nullptr);

  float min_weight_ = 0.0f;
  std::unordered_map<VoxelKey, BlockMesh> cache_;  // by pack_key(block coords)
  std::uint64_t meshed_generation_ = 0;            // volume generation at the last call
  const TsdfMap* volume_ = nullptr;                // the volume the cache belongs to
};

}  // namespace meshflow
