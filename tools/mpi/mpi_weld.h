#pragma once
// meshflow-mpi's weld: every rank welds the chunks it meshed (nodes/chunk/seam_weld.h), so
// rank 0 only concatenates the welded parts and writes.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "nodes/chunk/phase_times.h"
#include "nodes/chunk/seam_weld.h"
#include "runtime/triangle_mesh.h"

namespace meshflow::cli {

/// One chunk meshed by some rank: its position in the plan and its mesh, or its error.
struct ChunkResult {
  std::uint64_t position = 0;
  TriangleMesh mesh;
  std::vector<std::uint8_t> flags;  ///< chunk_vertex_flags()
  std::string error;                ///< non-empty: the chunk failed
  chunk::ChunkSeams seams;          ///< summarize_result()'s, on the rank that meshed it
  /// Where the mesh, flags and seams.vertex_piece wait for the weld (spill_result()); "": held.
  std::string spill;
  /// weld_on_ranks(): the welded part's first vertex and face row in the output, and the
  /// chunk's index in the weld plan.
  std::uint64_t first_vertex = 0, first_triangle = 0;
  std::size_t plan_index = 0;
  bool welded = false;  ///< mesh and flags are its welded part (weld_result())
};

/// Fills `result.seams` (summarize_seams() of its mesh and flags, feature vertices apart) when
/// the chunk did not fail: called where the chunk was meshed, as it arrives. O(V + T).
void summarize_result(ChunkResult& result, float voxel_size, int chunk_cells);

/// Writes a summarized result's mesh, flags and seams.vertex_piece to `path` (mesh_spill.h)
/// and frees them (result.spill = path), so a rank holds its chunks in flight, not every chunk
/// it meshed; a failed chunk is left as it is. Throws meshflow::Error naming `path`. O(V + T).
void spill_result(ChunkResult& result, const std::string& path);

/// Welds one result by `plan` (weld_on_ranks()'s with `weld_now` false): reads its spill back
/// (and removes the file) when it has one, then weld_chunk(): result.mesh becomes its welded
/// part, result.flags the kept vertices' bytes. Failed results are left. Thread-safe on
/// distinct results. Throws meshflow::Error for an unreadable spill. O(V + T).
void weld_result(ChunkResult& result, const chunk::WeldPlan& plan);

/// Welds this rank's chunk meshes `results` (each summarized: summarize_result(), perhaps
/// spilled: spill_result()) where they are (collective: every rank calls it once its chunks are
/// meshed). The summaries (seam
/// vertices and edges, a few counts: no mesh) go to rank 0 and from it to every rank; every rank
/// plans the weld of all chunks in position order from them (plan_weld(), seam-sized), then welds
/// its own chunks in parallel (weld_chunk()): each result's mesh becomes its part of the welded
/// mesh (the vertices kept in it, triangles in output indices), its flags the kept vertices' bytes.
/// Failed chunks are left out; each other result's first_vertex and first_triangle receive its
/// part's rows in the output. Concatenating every rank's parts in position order
/// (append_welded()) gives MeshStitcher::stitch()'s mesh of all chunks. Times "exchange"
/// (waiting for every rank's summaries), "seams" (the plan: serial on rank 0; the others, making
/// the same plan, count as waiting) and "weld" (parallel) on `clock`. Returns the plan (the
/// same on every rank; its per-seam-vertex targets dropped): counts, attributes, seam vertices
/// merged. With `weld_now` false the results are only placed (first rows, plan_index) and the
/// plan returned whole, for weld_result() as each part is written (memory: the parts being
/// written, not all of them; no "weld" phase). Throws meshflow::Error for a malformed message.
chunk::WeldPlan weld_on_ranks(std::vector<ChunkResult>& results, chunk::PhaseClock& clock, int rank,
                              int ranks, bool weld_now = true);

}  // namespace meshflow::cli
