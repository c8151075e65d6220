#pragma once
// Non-manifold vertices: where two sheets of a marching-cubes surface touch at a single grid
// point, or two pieces of an open scan's border meet corner to corner (a bow tie), one vertex
// joins two (or more) fans of triangles. Half-edge based steps need one fan per vertex. The
// clean step removes the triangles of the smaller fans (remove_smaller_fans, in
// runtime/vertex_triangles.h, which says why); splitting the vertex into one copy per fan, here,
// is the other repair.

#include <cstddef>

#include "runtime/triangle_mesh.h"
#include "runtime/vertex_triangles.h"

namespace meshflow {

/// Splits every vertex whose triangles form k > 1 fans into k vertices (remove_smaller_fans says
/// why the clean step removes the smaller fans instead): the fan with the lowest triangle index
/// keeps the vertex, the others get new vertices appended in vertex order (position, normal and
/// colour copied). Returns the number of vertices added. Parallel per vertex; deterministic. O(V +
/// T) time, plus O(V) memory per worker thread.
std::size_t split_non_manifold_vertices(TriangleMesh& mesh);

}  // namespace meshflow
