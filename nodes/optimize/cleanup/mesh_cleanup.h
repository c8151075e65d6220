#pragma once
// First optimization step: remove degenerate triangles and small disconnected components.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "runtime/triangle_mesh.h"

namespace meshflow {

/// What the clean step does at a vertex joining several fans of triangles (manifold_repair.h).
enum class NonManifoldVertexRepair {
  kNone,  ///< left as they are (the half-edge steps then refuse the mesh)
  /// The triangles of all fans but the largest are removed: no vertex moves or is added, and the
  /// mesh stays manifold when a reader welds coincident vertices (the default).
  kRemoveSmallerFans,
  /// One copy of the vertex per fan, at the same position: no triangle is lost, but a reader
  /// that welds coincident vertices on load (Open3D, trimesh) sees the non-manifold vertex again.
  kSplit,
};

struct CleanupConfig {
  /// Repeated vertex indices, zero area, a corner at a NaN or infinite position, duplicated faces.
  bool remove_degenerate = true;
  /// Connected components (by shared vertices) with fewer triangles are removed; 0 = keep all.
  std::size_t min_component_triangles = 20;
  /// Non-manifold vertices are made manifold so the half-edge steps can run.
  NonManifoldVertexRepair non_manifold_vertices = NonManifoldVertexRepair::kRemoveSmallerFans;
};

struct CleanupReport {
  std::size_t degenerate_triangles = 0;
  std::size_t duplicate_triangles = 0;
  std::size_t components = 0;  ///< components before removal
  std::size_t removed_components = 0;
  std::size_t removed_component_triangles = 0;
  std::size_t removed_vertices = 0;  ///< vertices no longer referenced, compacted away
  /// kRemoveSmallerFans: vertices with several fans met, and the triangles of their smaller fans
  std::size_t non_manifold_vertices = 0;
  std::size_t removed_fan_triangles = 0;
  std::size_t split_vertices = 0;  ///< kSplit: copies added at non-manifold vertices
};

/// Returns a cleaned copy of `mesh`: degenerate and duplicate triangles removed, then the
/// smaller fans of non-manifold vertices (kRemoveSmallerFans), then components smaller than
/// min_component_triangles (pieces that hung on by a vertex included); triangles kept in their
/// order, unreferenced vertices dropped and the rest renumbered in their order (normals and
/// colours follow). With kSplit, copies of non-manifold vertices are appended instead, and the
/// components the split separated that are too small are removed as well.
/// `held` (optional, one byte per vertex; kRemoveSmallerFans or kNone only): vertices whose
/// byte is non-zero keep all their fans, and components holding one stay whatever their size (a
/// chunk's seam, finished in place: graph/chunk_finish.h). `kept` (optional) receives
/// the input index of each output vertex (ascending), for per-vertex data to follow.
/// Parallel; deterministic. O(V + T) (a few passes for the fans).
TriangleMesh clean_mesh(const TriangleMesh& mesh, const CleanupConfig& config,
                        CleanupReport* report = nullptr,
                        const std::vector<std::uint8_t>* held = nullptr,
                        std::vector<std::uint32_t>* kept = nullptr);

}  // namespace meshflow
