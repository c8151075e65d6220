#pragma once
// A tile's coarser levels of detail from meshflow's progressive coder (nodes/compress/
// progressive_mesh.h): the tile coded progressively once, its base mesh and prefixes of its
// vertex splits decoded as the levels, so each is what a viewer streaming the tile's .mfc
// would see at that many triangles.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "nodes/chunk/mesh_tiles.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {

/// Which levels a tile gets.
struct TileLevelConfig {
  /// Coarser levels at most (0: none): the tile's triangles divided by ratio, ratio^2, ...
  std::size_t levels = 3;
  /// Triangles of a level over those of the next coarser one (> 1).
  double ratio = 4.0;
  /// A level of fewer triangles is left out (a tile smaller than this times `ratio` gets none).
  std::size_t min_triangles = 64;
  /// Lock the tile's border (every vertex on an edge of one of its triangles only: its seams
  /// with the neighbouring tiles and the mesh's own borders): no level removes or moves one, so
  /// any levels of two neighbouring tiles meet along their seam without a crack.
  bool lock_border = true;
};

/// Per vertex of `mesh`, 1 when it is on a border edge of the triangles without a repeated corner
/// (an edge of one of them only), else 0. Thread-safe. O(V + T).
std::vector<std::uint8_t> border_vertex_flags(const TriangleMesh& mesh);

/// The coarser levels of `tile`, coarse to fine, each of fewer triangles than the next and than
/// the tile: compress_progressive() with the base mesh at 1 / ratio^levels of the triangles,
/// decoded to its base mesh (the coarsest; QEM may stop above its target) and to the first
/// split reaching tile triangles / ratio^k for k = levels - 1 .. 1; levels below
/// `min_triangles` or not below the next are dropped. Positions as the progressive coder
/// decodes them (its default step: within 1/128 of the median edge of the tile's); normals
/// and colours kept where the tile has them. With lock_border, the border vertices
/// (border_vertex_flags()) are locked in the coder and every level has them exactly as the tile
/// does (position, normal, colour: bit for bit), with the tile's border edges. Thread-safe. Throws
/// meshflow::Error as the coder does. O(T log T) plus the decimation's cost (parallel) and one
/// decode per level.
std::vector<TriangleMesh> progressive_tile_levels(const TriangleMesh& tile,
                                                  const TileLevelConfig& config = {});

/// progressive_tile_levels() with `config`, as the tile writers take it.
chunk::CoarserLevels progressive_levels(const TileLevelConfig& config = {});

}  // namespace meshflow
