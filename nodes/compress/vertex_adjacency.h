#pragma once
// Vertex -> vertex adjacency of decoded triangles in compressed rows, sorted and without
// repeats: what the colour coder predicts from (the neighbours decoded before a vertex are a
// prefix of its row). Built by counting (no global sort), so it costs O(V + T).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "runtime/triangle_mesh.h"

namespace meshflow::compress {

/// Neighbours of vertex v: neighbour[first[v] .. first[v + 1]), ascending, each once.
struct VertexAdjacency {
  std::vector<std::uint32_t> first;      ///< vertex count + 1
  std::vector<std::uint32_t> neighbour;  ///< first.back() entries
};

/// The adjacency of `triangles` over `vertices` vertices: u and v are neighbours when some
/// triangle has the edge u-v (either direction) with u != v. Every corner must be below
/// `vertices` (the decoders' triangles are). Serial (a decoder runs it beside the positions:
/// nodes/compress/mesh_codec.cpp);
/// O(V + T x valence) time (each row sorted by insertion, its repeats skipped first: a vertex's
/// valence is small; rows past 64 entries by std::sort, so O(T log T) at worst) and O(V + T)
/// memory.
VertexAdjacency vertex_adjacency(std::size_t vertices, const std::vector<Triangle>& triangles);

}  // namespace meshflow::compress
