// The compression codecs' inner kernels against brute-force oracles: the vertex adjacency the
// colour coder predicts from, and the range coder at its edges (stream ends, long runs).

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "nodes/compress/range_coder.h"
#include "nodes/compress/vertex_adjacency.h"

namespace meshflow {
namespace {

// The adjacency by a global sort of every directed edge (what the colour coder used before).
compress::VertexAdjacency sorted_adjacency(std::size_t vertices,
                                           const std::vector<Triangle>& triangles) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
  for (const Triangle& t : triangles)
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3];
      if (a == b) continue;
      edges.emplace_back(a, b);
      edges.emplace_back(b, a);
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  compress::VertexAdjacency adj;
  adj.first.assign(vertices + 1, 0);
  for (const auto& e : edges) ++adj.first[e.first + 1];
  for (std::size_t v = 0; v < vertices; ++v) adj.first[v + 1] += adj.first[v];
  for (const auto& e : edges) adj.neighbour.push_back(e.second);
  return adj;
}

TEST(VertexAdjacency, MatchesASortOfAllEdges) {
  std::mt19937 rng(57);
  // Random triangles over few vertices (repeated edges, degenerate corners, one vertex with a
  // row past the insertion sort's 64 entries), unused vertices, and the empty mesh.
  for (std::size_t vertices : {0u, 1u, 5u, 40u, 3000u}) {
    for (std::size_t triangles : {0u, 1u, 17u, 4000u}) {
      if (vertices == 0 && triangles > 0) continue;
      std::uniform_int_distribution<std::uint32_t> pick(
          0, static_cast<std::uint32_t>(vertices == 0 ? 0 : vertices - 1));
      std::vector<Triangle> t(triangles);
      for (std::size_t i = 0; i < triangles; ++i) {
        t[i] = {pick(rng), pick(rng), pick(rng)};
        if (i % 7 == 0) t[i][1] = t[i][0];            // a degenerate corner
        if (i % 5 == 0 && vertices > 0) t[i][2] = 0;  // vertex 0's row grows long
      }
      const compress::VertexAdjacency fast = compress::vertex_adjacency(vertices, t);
      const compress::VertexAdjacency oracle = sorted_adjacency(vertices, t);
      EXPECT_EQ(fast.first, oracle.first) << vertices << " vertices, " << triangles;
      EXPECT_EQ(fast.neighbour, oracle.neighbour) << vertices << " vertices, " << triangles;
    }
  }
}

}  // namespace
}  // namespace meshflow
