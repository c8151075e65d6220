#pragma once
// Vertex -> triangle incidence of an indexed mesh (compressed rows), the adjacency that border
// detection and mesh clean-up walk.

#include <cstdint>
#include <vector>

#include "runtime/triangle_mesh.h"

namespace meshflow {

/// Triangles around each vertex: around(v) lists every triangle that has v as a corner, in
/// ascending triangle order (a triangle repeating v is listed once per repetition).
struct VertexTriangles {
  std::vector<std::uint32_t> offsets;    ///< vertex count + 1
  std::vector<std::uint32_t> triangles;  ///< 3 x triangle count

  /// First triangle index around vertex v.
  const std::uint32_t* begin(std::uint32_t v) const { return triangles.data() + offsets[v]; }
  /// One past the last triangle index around vertex v.
  const std::uint32_t* end(std::uint32_t v) const { return triangles.data() + offsets[v + 1]; }
};

/// Builds the incidence in parallel over consecutive triangle chunks (one per worker, at most
/// 8 and at most 3 T / V): each chunk counts, then places, its own triangles' corners through
/// per-chunk row positions, so no atomics are needed, every triangle is read twice in all, and
/// the result is the same for any thread count. Corners indexing no vertex (>= the vertex
/// count) are left out.
/// O(T + V x chunks) time and memory (the chunks' positions take at most the output's size).
VertexTriangles vertex_triangles(const TriangleMesh& mesh);
/// The same for bare triangles over `vertex_count` vertices.
VertexTriangles vertex_triangles(const std::vector<Triangle>& triangles, std::size_t vertex_count);

/// The fans around every vertex (triangles around it joined through shared edges, i.e. shared
/// corners other than the vertex): writes fan[s] for every slot s of `around` (0 = the fan
/// holding the vertex's lowest triangle, then in order of their lowest triangles) and returns
/// the fan count of each vertex (0 for an unused vertex). `around` is vertex_triangles() of
/// `triangles`. Parallel per vertex; deterministic. O(V + T), plus O(V) memory per worker where
/// a vertex has more than 16 triangles.
std::vector<std::uint32_t> vertex_fans(const std::vector<Triangle>& triangles,
                                       const VertexTriangles& around,
                                       std::vector<std::uint32_t>& fan);

// Non-manifold vertices: where two sheets of a marching-cubes surface touch at a single grid
// point, or two pieces of an open scan's border meet corner to corner (a bow tie), one vertex
// joins two (or more) fans of triangles. Half-edge based steps need one fan per vertex.
//
// The clean step and the per-frame triangulations remove the triangles of the smaller fans
// (remove_smaller_fans). Splitting the vertex into one copy per fan (split_non_manifold_vertices)
// changes no geometry but leaves coincident vertices, and readers that weld vertices on load
// (Open3D's OBJ and glTF readers, trimesh, MeshLab's "merge close vertices") join them into the
// same non-manifold vertex again: the file is manifold only to a reader that keeps indices as
// written. Moving the copies apart does not help either: a move small enough to change no geometry
// is undone by a welding tolerance or by a writer's decimal digits, a larger one makes spikes or
// self-intersections. The smaller fans are a few triangles (a Kinect frame's marching-cubes mesh:
// bow ties of 1-5 triangles on the scan's border at 73 vertices, about 150 of 197 000 triangles);
// on a closed surface the hole left is a small border loop that the holes step closes.

/// What remove_smaller_fans() did.
struct FanRemovalCounts {
  std::size_t vertices = 0;   ///< non-manifold vertices met (over all passes)
  std::size_t triangles = 0;  ///< triangles removed
  std::size_t passes = 0;     ///< passes until every vertex had one fan
};

/// Removes, at every vertex whose triangles form k > 1 fans (triangles around the vertex joined
/// through shared edges), the triangles of all fans but the largest (the most triangles; of
/// equal ones, the fan holding the lowest triangle index), keeping the other triangles in
/// order; corners index `vertex_count` vertices. Removing a fan can leave one of its other
/// corners with two fans, so passes repeat, each over the corners of the triangles the previous
/// one removed, until every vertex has one fan (two or three passes on scanned meshes).
/// Vertices are not touched: no position moves and none is added. Adds to `counts` when given.
/// `held` (optional, one byte per vertex): vertices whose byte is non-zero are left with all
/// their fans (a chunk's seam vertex, whose other fans lie in the neighbouring chunk).
/// Deterministic. O(V + T) for the first pass (fans counted in parallel per vertex; O(V) memory
/// per worker thread only where a vertex has more than 16 triangles), then O(triangles around the
/// vertices looked at) per pass, serial.
void remove_smaller_fans(std::vector<Triangle>& triangles, std::size_t vertex_count,
                         FanRemovalCounts* counts = nullptr,
                         const std::vector<std::uint8_t>* held = nullptr);

}  // namespace meshflow
