#pragma once
// A welded mesh cut along the chunk grid into tiles, for scenes too large to load as one file:
// one mesh file per chunk plus an index (tiles.json), so a viewer loads the tiles it looks at.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "nodes/chunk/chunk_grid.h"
#include "nodes/io/ply_mesh_file.h"
#include "runtime/triangle_mesh.h"

namespace meshflow::chunk {

/// One chunk's part of a mesh.
struct MeshTile {
  Eigen::Vector3i chunk = Eigen::Vector3i::Zero();  ///< chunk index (ChunkGrid)
  /// Its triangles in the mesh's order, vertices renumbered in order of first use (normals and
  /// colours kept); a vertex used by triangles of several tiles is copied into each.
  TriangleMesh mesh;
};

/// The triangles of `mesh` grouped by the chunk owning the cell of their centroid, so every
/// triangle is in exactly one tile; tiles in Morton order of their chunk (morton_code), none
/// empty. Thread-compatible. O(V + T log T).
std::vector<MeshTile> split_into_tiles(const TriangleMesh& mesh, const ChunkGrid& grid);

/// The file name of `chunk`'s tile: "tile_I_J_K.glb". O(1).
std::string tile_file_name(const Eigen::Vector3i& chunk);

/// A chunk's tile read back from the finished rows of a streamed output `file`: face rows
/// [first_triangle, first_triangle + triangles) (the chunk's welded, finished part) and the
/// vertices they use (seam vertices kept by an earlier chunk copied in), renumbered in order
/// of first use, normals and colours as the file has them. Throws meshflow::Error on a failed
/// read. O(triangles) plus one read per run of consecutive vertex rows.
MeshTile read_tile(const io::PlyMeshFile& file, const Eigen::Vector3i& chunk,
                   std::uint64_t first_triangle, std::uint64_t triangles);

/// write_tiles() one tile at a time: memory holds the index, not the tiles.
class TileWriter {
 public:
  /// Creates `dir` (tiles.json is written by finish()). Throws meshflow::Error naming it.
  TileWriter(std::string dir, const ChunkGrid& grid, const Eigen::Vector3d& origin);
  /// Writes `tile` to DIR/tile_file_name() (glTF binary, `origin` as its node's translation;
  /// an empty tile is skipped) and adds it to the index. Not thread-safe. O(tile).
  void add(const MeshTile& tile);
  /// Writes DIR/tiles.json (atomically). Returns the tiles written. O(tiles).
  std::size_t finish();

 private:
  std::string dir_, index_;
  Eigen::Vector3d origin_;
  std::size_t tiles_ = 0;
};

/// Writes each tile to DIR/tile_file_name() (glTF binary, `origin` as its node's translation)
/// and then DIR/tiles.json, the index: {"format": "meshflow-tiles-1", "origin": [x, y, z],
/// "voxel", "chunk_metres", "tiles": [{"chunk": [i, j, k], "file", "vertices", "triangles",
/// "min": [x, y, z], "max": [x, y, z]}]}, bounds in the tiles' coordinates (add `origin` for the
/// world's). Creates DIR; every file appears complete or not at all. Throws meshflow::Error
/// naming the file that cannot be written. O(V + T).
void write_tiles(const std::string& dir, const std::vector<MeshTile>& tiles, const ChunkGrid& grid,
                 const Eigen::Vector3d& origin);

}  // namespace meshflow::chunk
