#pragma once
// Joining chunk meshes into one: vertices that marching cubes put on the same lattice edge of
// the global grid are the same vertex, whichever chunk made them, so meshes of neighbouring
// chunks share their seam vertices and the joined mesh is manifold across seams.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "nodes/chunk/seam_weld.h"
#include "runtime/triangle_mesh.h"

namespace meshflow::chunk {

/// The key of the lattice edge (segment between two neighbouring grid corners) that `p` lies
/// on: two coordinates on grid planes (within 1e-4 voxel: interpolation rounds them by an ulp)
/// and the third at least 5e-4 voxel from any (extraction clamps the crossing to [1e-3, 1 -
/// 1e-3] of the edge); packed as the lower corner's key times 3 plus the axis. Returns
/// UINT64_MAX for a point on no lattice edge (a feature vertex inside a cell, a diagonal of
/// marching tetrahedra, a moved vertex). O(1).
std::uint64_t lattice_edge_key(const Eigen::Vector3f& p, float voxel_size);

/// Whether the vertex of lattice edge `key` (lattice_edge_key(); UINT64_MAX: none) lies on a
/// boundary plane of chunks of `chunk_cells` cells (a coordinate of the edge's lower corner,
/// other than along the edge, divisible by chunk_cells): a seam vertex, which the chunks on both
/// sides of the plane make. O(1).
bool on_chunk_seam(std::uint64_t key, int chunk_cells);

/// Bit a set when the vertex of lattice edge `key` (UINT64_MAX: none, 0) lies on a chunk
/// boundary plane across axis a (a coordinate of its lower corner, other than along the edge,
/// divisible by `chunk_cells` > 0). O(1).
unsigned seam_plane_axes(std::uint64_t key, int chunk_cells);

/// One byte per vertex of `vertices`: 1 for a seam vertex (on_chunk_seam() of its lattice edge
/// key at `voxel_size`) whose `apart` byte (optional, one per vertex: feature vertices) is 0.
/// Parallel; O(V).
std::vector<std::uint8_t> seam_vertices(const std::vector<Eigen::Vector3f>& vertices,
                                        float voxel_size, int chunk_cells,
                                        const std::vector<std::uint8_t>& apart = {});

/// Collects chunk meshes and welds them (not thread-safe; add in a fixed order for a
/// deterministic result).
///
/// Orientation: a chunk whose normals were estimated and oriented on its own (no normals in the
/// input, no sensor) can come out wound the other way round than its neighbour. Given the chunk
/// edge (`chunk_cells`), every connected piece of every added mesh is related to the pieces it
/// shares seam edges with (edges on a chunk boundary plane between two lattice-edge vertices):
/// the same way round when most shared edges run opposite ways (consistent winding), turned
/// when most run the same way. stitch() solves these relations with a union-find that keeps
/// each piece's parity (the strongest relations first; one that contradicts the stronger ones
/// is dropped), then turns, in each connected group, whichever side holds fewer triangles: the
/// chunks' own majority decides which side is outside, whatever the order they came in.
class MeshStitcher {
 public:
  /// `voxel_size` of the grid every chunk mesh was extracted on, metres; `chunk_cells` the
  /// chunk edge in cells (0: no orientation relations).
  /// `apart_flags`: vertices whose flag byte (add()'s vertex_flags) has any of these bits are
  /// never merged, even when they lie on a lattice edge (extended marching cubes' feature
  /// vertices, clamped to their cell's box, can sit on one beside the edge's own vertex).
  explicit MeshStitcher(float voxel_size, int chunk_cells = 0, std::uint8_t apart_flags = 0)
      : voxel_size_(voxel_size), chunk_cells_(chunk_cells), apart_flags_(apart_flags) {}

  /// Appends a chunk's mesh (vertices in the common local frame; normals and colours kept when
  /// every chunk has them) and optionally a byte per vertex (`vertex_flags`, e.g. Frame::
  /// beyond_data; kept when every chunk gives them); summarizes its seam (summarize_seams(),
  /// seam_weld.h: with `chunk_cells`, its pieces and their seam edges). The mesh is held until
  /// stitch(). O(V + T).
  void add(TriangleMesh mesh, std::vector<std::uint8_t> vertex_flags = {});

  /// The joined mesh: pieces turned as the relations say, vertices with one lattice edge key
  /// merged (the first chunk's copy kept; with `chunk_cells`, only seam vertices, on_chunk_seam(),
  /// are looked at: a chunk's own mesh has one vertex per lattice edge), vertices on no lattice
  /// edge kept apart, unused vertices dropped, triangles in the order added (plan_weld() and
  /// weld_chunk() of seam_weld.h; each chunk freed once welded). `merged` (optional) receives
  /// the number of seam vertices merged, `vertex_flags` (optional) the kept vertices' flags
  /// (empty unless every chunk gave them), `turned` (optional) the number of triangles turned
  /// over. O(V + T + S log S + R log R) for S seam vertices and R relations.
  TriangleMesh stitch(std::size_t* merged = nullptr,
                      std::vector<std::uint8_t>* vertex_flags = nullptr,
                      std::size_t* turned = nullptr);

 private:
  float voxel_size_;
  int chunk_cells_;
  std::uint8_t apart_flags_;
  std::vector<TriangleMesh> meshes_;
  std::vector<std::vector<std::uint8_t>> flags_;
  std::vector<ChunkSeams> seams_;
};

}  // namespace meshflow::chunk
