#pragma once
// Welding chunk meshes where they were meshed. MeshStitcher's weld split in three so that MPI
// ranks weld their own chunks and rank 0 only concatenates:
//
//   summarize_seams(chunk)   on the chunk's rank: its seam vertices (lattice edge keys), its
//                            connected pieces and their seam edges; O(V + T), kept small
//                            (seam only) for the exchange;
//   plan_weld(all summaries) on every rank, from the seam summaries alone: which copy of each
//                            seam vertex is kept (the first chunk's), the output index of every
//                            kept seam vertex, each chunk's first output vertex and which pieces
//                            turn over; O(S log S + R log R) for S seam vertices, R relations;
//   weld_chunk(chunk, plan)  on the chunk's rank: its kept vertices and its triangles in output
//                            indices, turned as planned; O(V + T).
//
// Concatenating weld_chunk()'s results in chunk order gives exactly MeshStitcher::stitch()'s
// mesh (which is built on these functions).

#include <cstdint>
#include <vector>

#include "runtime/triangle_mesh.h"

namespace meshflow::chunk {

/// One occurrence of a seam edge (both ends seam vertices on one chunk boundary plane) in a
/// chunk's triangles, in triangle order.
struct SeamEdge {
  std::uint64_t lower = 0, higher = 0;  ///< the ends' lattice edge keys, ordered
  std::uint32_t piece = 0;              ///< the chunk's own piece the triangle belongs to
  std::uint8_t direction = 0;           ///< 1: the triangle runs from `lower` to `higher`
};

/// What plan_weld() needs of one chunk (the seam; a few numbers for the rest), and what its
/// owner keeps for weld_chunk() (`vertex_piece`, never sent).
struct ChunkSeams {
  std::uint32_t vertices = 0;    ///< the chunk mesh's vertex count
  std::uint32_t used_apart = 0;  ///< vertices without a seam key that a triangle uses (kept)
  bool normals = false, colors = false, flags = false;  ///< per-vertex attributes it has
  /// Connected pieces (triangles sharing a vertex; an unused vertex is a piece of its own),
  /// numbered in the order of their lowest vertex: each one's triangle count.
  std::vector<std::uint64_t> piece_triangles;
  // Seam vertices (with a lattice edge key on a chunk boundary plane), in vertex order:
  std::vector<std::uint32_t> seam_index;         ///< the vertex
  std::vector<std::uint64_t> seam_key;           ///< its lattice edge key
  std::vector<std::uint8_t> seam_used;           ///< 1 when a triangle of this chunk uses it
  std::vector<std::uint32_t> used_apart_before;  ///< used vertices without a key before it
  std::vector<SeamEdge> edges;                   ///< seam edge occurrences, triangle order
  std::vector<std::uint32_t> vertex_piece;       ///< per vertex, its piece (owner only)
};

/// The seam summary of one chunk's mesh extracted on the global grid of `voxel_size` metres in
/// chunks of `chunk_cells` cells (0: every lattice edge vertex is a seam vertex and no edge is
/// related). `vertex_flags` (one byte per vertex, or empty): vertices with any of `apart_flags`
/// get no key (never merged). Thread-safe on distinct meshes; parallel key computation, O(V + T).
ChunkSeams summarize_seams(const TriangleMesh& mesh, const std::vector<std::uint8_t>& vertex_flags,
                           float voxel_size, int chunk_cells, std::uint8_t apart_flags);

/// The weld of all chunks, decided from their summaries in chunk order.
struct WeldPlan {
  std::vector<std::uint32_t> vertex_offset;  ///< per chunk: its first output vertex
  std::vector<std::uint32_t> piece_offset;   ///< per chunk: its first global piece
  std::vector<std::uint8_t> turn;            ///< per global piece: wound the other way round
  /// Per chunk, per seam vertex (ChunkSeams::seam_index order): the output index of the kept
  /// copy (the first chunk's), or UINT32_MAX when no triangle uses any copy.
  std::vector<std::vector<std::uint32_t>> seam_target;
  std::uint64_t vertices = 0;   ///< output vertices
  std::uint64_t triangles = 0;  ///< output triangles
  std::size_t merged = 0;       ///< seam copies merged into an earlier chunk's
  std::size_t turned = 0;       ///< triangles turned over
  bool normals = false, colors = false, flags = false;  ///< kept when every chunk has them
};

/// MeshStitcher's orientation and weld from the chunks' summaries (`chunks` in the order the
/// meshes are joined): the first copy of a seam key is kept; pieces related through seam edges
/// are turned as MeshStitcher's class comment says. Deterministic; not thread-safe on one
/// `chunks`. O(S log S + R log R + pieces + chunks).
WeldPlan plan_weld(const std::vector<const ChunkSeams*>& chunks);

/// Chunk `index`'s part of the welded mesh: its kept vertices (with normals, colours, flags as
/// `plan` keeps them; normals of turned pieces negated) and its triangles in output indices,
/// turned as planned; `flags` receives the kept vertices' bytes of `vertex_flags` when
/// plan.flags. Thread-safe (distinct chunks weld at once). O(V + T).
TriangleMesh weld_chunk(const TriangleMesh& mesh, const std::vector<std::uint8_t>& vertex_flags,
                        const ChunkSeams& seams, const WeldPlan& plan, std::size_t index,
                        std::vector<std::uint8_t>* flags = nullptr);

/// Appends `part` (weld_chunk()'s result, triangles already in output indices) to `joined`.
/// O(V + T) of the part.
void append_welded(TriangleMesh& joined, const TriangleMesh& part);

}  // namespace meshflow::chunk
