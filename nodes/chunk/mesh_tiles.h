#pragma once
// A welded mesh cut along the chunk grid into tiles, for scenes too large to load as one file:
// one mesh file per chunk, each also at coarser levels of detail, plus an index (tiles.json), so
// a viewer loads the tiles it looks at, each at the level its distance asks for.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
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

/// One level of detail of a tile, as the index lists it.
struct TileLevel {
  std::string file;              ///< its file in the tiles' directory
  std::uint64_t triangles = 0;   ///< its triangles
  std::uint64_t bytes = 0;       ///< its file's size
  double geometric_error = 0.0;  ///< metres: level_error() against the tile, 0 for the tile
};

/// What the index says of one tile (chunk::write_tile()'s result, small enough to send).
struct TileRecord {
  Eigen::Vector3i chunk = Eigen::Vector3i::Zero();
  std::string file;  ///< the full tile's file (the last level's)
  std::uint64_t vertices = 0, triangles = 0;
  Eigen::Vector3f min = Eigen::Vector3f::Zero(), max = Eigen::Vector3f::Zero();  ///< its bounds
  std::vector<TileLevel> levels;  ///< coarse to fine, the last the tile itself
};

/// Makes a tile's coarser levels: meshes of fewer triangles than `tile` approximating it,
/// coarse to fine (graph/tile_levels.h: the progressive coder's). Called on one tile at a time;
/// must be thread-safe when tiles are written in parallel.
using CoarserLevels = std::function<std::vector<TriangleMesh>(const TriangleMesh& tile)>;

/// The file name of level `level` (0 the coarsest) of `chunk`'s tile below the full tile:
/// "tile_I_J_K_lodL.glb". O(1).
std::string tile_level_file_name(const Eigen::Vector3i& chunk, std::size_t level);

/// How far `coarse` strays from `fine`, metres: the largest distance from a vertex of either
/// mesh to the other's surface (the symmetric Hausdorff distance sampled at both meshes'
/// vertices; fine meshes' vertices sample their surface at the mesh's resolution). 0 for two
/// meshes with the same vertices on each other's triangles; +inf when either has no triangle.
/// Thread-safe. O((V_fine + V_coarse) x the triangles near each query).
double level_error(const TriangleMesh& fine, const TriangleMesh& coarse);

/// Writes `tile` to DIR/tile_file_name() and each of `coarser` (coarse to fine, each of fewer
/// triangles than the next) to DIR/tile_level_file_name() (glTF binary, `origin` as the node's
/// translation), and returns the tile's index record: every level with its triangles, its
/// file's bytes and its geometric error, level_error() against the tile raised to the next
/// finer level's where that is larger (so errors never grow from coarse to fine; the tile's own
/// is 0). Every file appears complete or not at all. Thread-safe for distinct tiles. Throws
/// meshflow::Error naming a file that cannot be written, or for an empty tile. O(tile).
TileRecord write_tile(const std::string& dir, const MeshTile& tile, const Eigen::Vector3d& origin,
                      const std::vector<TriangleMesh>& coarser = {});

/// Writes DIR/tiles.json (atomically), the index of `records` (in their order) for tiles cut
/// on `grid` whose coordinates are relative to `origin`:
///   {"format": "meshflow-tiles-2", "origin": [x, y, z], "voxel", "chunk_metres",
///    "tiles": [{"chunk": [i, j, k], "file", "vertices", "triangles", "min": [x, y, z],
///               "max": [x, y, z], "levels": [{"file", "triangles", "bytes",
///               "geometric_error"}, ...]}]}
/// (bounds in the tiles' coordinates: add `origin` for the world's; levels coarse to fine, the
/// last the tile's own file with geometric_error 0; docs/OUT_OF_CORE.md), and DIR/tileset.json
/// (write_tileset_json()). Throws meshflow::Error naming the file. O(records).
void write_tile_index(const std::string& dir, const ChunkGrid& grid, const Eigen::Vector3d& origin,
                      const std::vector<TileRecord>& records);

/// Writes DIR/tileset.json (atomically), the same tiles as a 3D Tiles 1.1 tileset with glTF
/// content, for generic viewers: a root without content (geometricError: the tiles' bounding
/// box's diagonal, at least every coarsest level's error) whose transform turns the glTF
/// content, which 3D Tiles reads y-up, back to the tiles' z-up coordinates; under it per tile
/// a chain of tiles with REPLACE refinement, the coarsest level first, each level's content its
/// file and its geometricError the index's geometric_error (the tile's own file: 0). Bounding
/// boxes: the tile's, padded by `grid`'s voxel (the coarser levels' quantised positions), with
/// `origin` added, in the root's frame. Throws meshflow::Error naming the file. O(records).
void write_tileset_json(const std::string& dir, const ChunkGrid& grid,
                        const Eigen::Vector3d& origin, const std::vector<TileRecord>& records);

/// Creates `dir` and every directory above it. Throws meshflow::Error naming it. O(1).
void create_tile_directory(const std::string& dir);

/// Reads the tiles `read(0)`, ..., `read(count - 1)` (in order, one call at a time) and writes
/// each with the coarser levels `levels` makes (write_tile(); an empty tile is skipped), at
/// most `in_flight` (>= 1) tiles at once, the tiles in flight in parallel; returns their
/// records in read order. Memory: `in_flight` tiles. The files are the same for any
/// `in_flight` and thread count. Throws the first meshflow::Error of a read or a write.
/// O(tiles) plus the levels' cost.
std::vector<TileRecord> write_tiles_in_flight(const std::string& dir, std::size_t count,
                                              const std::function<MeshTile(std::size_t)>& read,
                                              const Eigen::Vector3d& origin,
                                              const CoarserLevels& levels, std::size_t in_flight);

/// Writes each tile with its coarser levels (`levels`, if set; the tiles in parallel, the files
/// the same at any thread count) and then DIR/tiles.json (write_tile_index()). Creates DIR;
/// every file appears complete or not at all. Throws meshflow::Error naming the file that cannot
/// be written. O(V + T) plus the levels' cost.
void write_tiles(const std::string& dir, const std::vector<MeshTile>& tiles, const ChunkGrid& grid,
                 const Eigen::Vector3d& origin, const CoarserLevels& levels = {});

}  // namespace meshflow::chunk
