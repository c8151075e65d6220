#include "nodes/compress/vertex_adjacency.h"

#include <algorithm>

namespace meshflow::compress {

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
  adj.first.resize(vertices + 1);
  std::uint32_t* const n = adj.neighbour.data();
  std::uint32_t out = 0;
  for (std::size_t v = 0; v < vertices; ++v) {
    std::uint32_t* const begin = n + slot[v];
    std::uint32_t* const end = n + slot[v + 1];
    if (end - begin > 32) {
      std::sort(begin, end);
    } else {
      for (std::uint32_t* i = begin + (begin != end); i < end; ++i) {
        const std::uint32_t x = *i;
        std::uint32_t* j = i;
        for (; j > begin && *(j - 1) > x; --j) *j = *(j - 1);
        *j = x;
      }
    }
    adj.first[v] = out;
    for (std::uint32_t* i = begin; i < end; ++i)
      if (out == adj.first[v] || n[out - 1] != *i) n[out++] = *i;
  }
  adj.first[vertices] = out;
  adj.neighbour.resize(out);
  return adj;
}

}  // namespace meshflow::compress
