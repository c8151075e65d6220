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

}  // namespace meshflow
