#pragma once
// First optimization step: remove degenerate triangles and small disconnected components.

#include <cstddef>

#include "runtime/triangle_mesh.h"

namespace meshflow {

struct CleanupConfig {
  /// Repeated vertex indices, zero area, a corner at a NaN or infinite position, duplicated faces.
  bool remove_degenerate = true;
  /// Connected components (by shared vertices) with fewer triangles are removed; 0 = keep all.
  std::size_t min_component_triangles = 20;
  /// Vertices joining several fans of triangles are split, one copy per fan (manifold_repair.h),
  /// so the half-edge steps can run.
  bool split_non_manifold_vertices = true;
};

struct CleanupReport {
  std::size_t degenerate_triangles = 0;
  std::size_t duplicate_triangles = 0;
  std::size_t components = 0;  ///< components before removal
  std::size_t removed_components = 0;
  std::size_t removed_component_triangles = 0;
  std::size_t removed_vertices = 0;  ///< vertices no longer referenced, compacted away
  std::size_t split_vertices = 0;    ///< copies added at non-manifold vertices
};

/// Returns a cleaned copy of `mesh`: triangles kept in their order, unreferenced vertices
/// dropped and the rest renumbered in their order (normals and colours follow), then copies of
/// non-manifold vertices appended; components the split separated that are smaller than
/// min_component_triangles are removed too (no small piece survives the step).
/// Parallel; deterministic. O(V + T).
TriangleMesh clean_mesh(const TriangleMesh& mesh, const CleanupConfig& config,
                        CleanupReport* report = nullptr);

}  // namespace meshflow
