#pragma once
// Non-manifold vertices: where two sheets of a marching-cubes surface touch at a single grid
// point, one vertex joins two (or more) fans of triangles. Half-edge based steps need one fan
// per vertex, so such a vertex is split into one copy per fan (same position), which changes
// no geometry.

#include <cstddef>

#include "runtime/triangle_mesh.h"

namespace meshflow {

/// Splits every vertex whose triangles form k > 1 fans (triangles around the vertex joined
/// through shared edges) into k vertices: the fan with the lowest triangle index keeps the
/// vertex, the others get new vertices appended in vertex order (position, normal and colour
/// copied). Returns the number of vertices added. Parallel per vertex; deterministic.
/// O(V + T) time, plus O(V) memory per worker thread.
std::size_t split_non_manifold_vertices(TriangleMesh& mesh);

}  // namespace meshflow
