#pragma once
// Finishing a chunk's mesh where the chunk was meshed (its rank, its graph thread) instead of
// on the stitched mesh: extended marching cubes' edge flips, the rim trim and the clean and
// holes steps run on the chunk with its seam vertices held fixed (seam_vertices(): the lattice
// edge vertices on a chunk boundary plane, which the neighbouring chunk makes too), so both
// sides of a seam leave it as extraction made it and the stitcher welds it as before. What
// is left for the stitched mesh is the seam itself (finish_seams(): the flips across seam
// edges and the normals around them), O(seam) after one scan of the triangles.
//
// The result equals finishing the stitched mesh but where a decision spans a seam:
//   - the rim trim peels nothing at a seam vertex beyond the data (nor what that uncovers);
//   - non-manifold fans at a seam vertex are kept; a component touching a seam is kept
//     whatever its size (components below --min-component that cross a seam stay);
//   - a hole whose border loop runs through a seam vertex stays open, and feature lines are
//     detected per chunk (those cut by a seam can fall below their minimum length);
//   - flips next to a seam are decided per chunk first, then across the seam.
// tests/graph/test_chunked_reconstruction.cpp bounds the difference on the city scene.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "nodes/optimize/optimize_mesh.h"
#include "runtime/triangle_mesh.h"

namespace meshflow::chunk {

struct ChunkFinishConfig {
  float voxel_size = 0.0f;  ///< metres, of the global grid the chunk was extracted on
  int chunk_cells = 0;      ///< chunk edge in cells (seam planes at its multiples)
  bool trim_rim = false;    ///< peel the rim off where `beyond` says so
  /// The clean and holes steps (no other step can hold vertices: optimize_mesh()'s held form).
  OptimizeConfig optimize;
};

struct ChunkFinishReport {
  std::size_t seam_vertices = 0;  ///< held fixed
  std::size_t flips = 0;          ///< extended marching cubes' flips inside the chunk
  std::size_t rim_trimmed = 0;    ///< triangles peeled off the rim
  OptimizeReport optimize;
};

/// Finishes one chunk's extracted mesh (vertices in the common local frame) with its seam
/// vertices held fixed: flips between its feature vertices (`features`, one byte per vertex or
/// empty; vertex normals recomputed after), the rim trim where `beyond` (one per vertex or
/// empty) marks vertices beyond the data (seam vertices never count as beyond), then
/// config.optimize's clean and holes steps. `features` receives the flags of the result's
/// vertices (empty when none were given). Throws meshflow::Error for a step that cannot hold
/// vertices. Not thread-safe on one mesh; chunks finish in parallel. O(V + T) plus the steps'
/// costs on the chunk.
TriangleMesh finish_chunk_mesh(const TriangleMesh& mesh, const std::vector<std::uint8_t>& beyond,
                               std::vector<std::uint8_t>& features, const ChunkFinishConfig& config,
                               ChunkFinishReport* report = nullptr);

/// The seam's part of the finish on the stitched mesh of chunks finished in place: extended
/// marching cubes' flips across seam edges (both ends seam vertices; `features` one byte per
/// vertex), then the vertex normals of the seam vertices and their neighbours from their whole
/// fans (when the mesh has normals). Only the triangles touching those vertices are looked at
/// after one parallel scan. Returns the flips made; with no feature vertex, does nothing.
/// O(T / threads + S log S) for S triangles near the seams.
std::size_t finish_seams(TriangleMesh& mesh, const std::vector<std::uint8_t>& features,
                         float voxel_size, int chunk_cells);

/// finish_seams()'s work on the seams' neighbourhood `around`: the triangles of the stitched
/// mesh touching a seam vertex's neighbour, in mesh order, over their vertices in the order of
/// their mesh index (`features`, `seam` one byte each). Flips between feature vertices whose
/// edge joins two seam vertices, then recomputes `around`'s normals (when it has them); the
/// caller copies back the triangles and the normals of the vertices next to a seam. Returns
/// the flips made. O(S log S).
std::size_t finish_seam_neighbourhood(TriangleMesh& around,
                                      const std::vector<std::uint8_t>& features,
                                      const std::vector<std::uint8_t>& seam);

}  // namespace meshflow::chunk
