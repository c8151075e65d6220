#include "nodes/compress/vertex_adjacency.h"

#include <algorithm>

namespace meshflow::compress {

namespace {
// Rows with more entries than this (repeats included) are sorted by std::sort, not insertion.
constexpr std::uint32_t kAdjacencyLongRow = 64;
}  // namespace

VertexAdjacency vertex_adjacency(std::size_t vertices, const std::vector<Triangle>& triangles) {
  // Rows with repeats first (each triangle edge in both directions), then each row sorted and
  // its repeats squeezed out in place, the rows moved down over the gaps.
  std::vector<std::uint32_t> slot(vertices + 1, 0);
  for (const Triangle& t : triangles)
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[k == 2 ? 0 : k + 1];
      if (a == b) continue;
      ++slot[a + 1];
      ++slot[b + 1];
    }
  for (std::size_t v = 0; v < vertices; ++v) slot[v + 1] += slot[v];
  VertexAdjacency adj;
  adj.neighbour.resize(slot[vertices]);
  std::vector<std::uint32_t> next(slot.begin(), slot.end() - 1);
  for (const Triangle& t : triangles)
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[k == 2 ? 0 : k + 1];
      if (a == b) continue;
      adj.neighbour[next[a]++] = b;
      adj.neighbour[next[b]++] = a;
    }
  // Each row in place: its first copy of each neighbour (a stamp per vertex marks those met in
  // the row) inserted into the row's sorted prefix; the rows move down over the repeats' gaps.
  adj.first.resize(vertices + 1);
  std::uint32_t* const n = adj.neighbour.data();
  std::vector<std::uint32_t> stamp(vertices, ~0u);
  std::uint32_t out = 0;
  for (std::size_t v = 0; v < vertices; ++v) {
    const auto row = static_cast<std::uint32_t>(v);
    const std::uint32_t begin = out;
    adj.first[v] = begin;
    // A long row (a vertex on very many triangles) is sorted once its repeats are out.
    const bool insert = slot[v + 1] - slot[v] <= kAdjacencyLongRow;
    for (std::uint32_t i = slot[v]; i < slot[v + 1]; ++i) {
      const std::uint32_t x = n[i];
      if (stamp[x] == row) continue;
      stamp[x] = row;
      std::uint32_t j = out++;
      if (insert)
        for (; j > begin && n[j - 1] > x; --j) n[j] = n[j - 1];
      n[j] = x;
    }
    if (!insert) std::sort(n + begin, n + out);
  }
  adj.first[vertices] = out;
  adj.neighbour.resize(out);
  return adj;
}

}  // namespace meshflow::compress
