// The compression codecs' inner kernels against brute-force oracles: the vertex adjacency the
// colour coder predicts from and its neighbour weights, the quantiser's rounding, the decoder's
// two jobs side by side, and the range coder at its edges (stream ends, long runs).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "nodes/compress/color_coder.h"
#include "nodes/compress/quantizer.h"
#include "nodes/compress/range_coder.h"
#include "nodes/compress/side_by_side.h"
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

// The quantiser's rounding without a library call is std::round's on every double it takes,
// the values just below a half (where x + 0.5 rounds up) and exact halves included.
TEST(Quantizer, RoundingMatchesStdRound) {
  std::vector<double> xs = {0.0,
                            0.5,
                            1.5,
                            2.5,
                            0.49999999999999994,
                            1.4999999999999998,
                            -0.5,
                            -1.5,
                            -0.3,
                            1e15 + 0.5,
                            4503599627370495.5,
                            4503599627370496.0,
                            9e18,
                            -9e18,
                            1e300,
                            std::numeric_limits<double>::infinity()};
  for (double k = 0; k < 70000; k += 1.0) {
    xs.push_back(k + 0.5);
    xs.push_back(std::nextafter(k + 0.5, 0.0));
    xs.push_back(std::nextafter(k + 0.5, 1e9));
  }
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> any(-10.0, 20000.0);
  for (int i = 0; i < 100000; ++i) xs.push_back(any(rng));
  for (double x : xs) EXPECT_EQ(compress::Quantizer::round_half_away(x), std::round(x)) << x;
}

// The colour weights against the formula in 64-bit division: ((nearest + 1) << 16) /
// (d + 1), squared, over the neighbours decoded before each vertex; on grids near and far
// (the 32-bit path and the 64-bit one).
TEST(ColorCoding, NeighbourWeightsMatchTheFormula) {
  std::mt19937 rng(7);
  for (std::int32_t spread : {3, 200, 1 << 20}) {
    const std::uint32_t vertices = 500;
    std::uniform_int_distribution<std::int32_t> coordinate(0, spread);
    std::uniform_int_distribution<std::uint32_t> pick(0, vertices - 1);
    std::vector<std::array<std::int32_t, 3>> grid(vertices);
    for (auto& g : grid) g = {coordinate(rng), coordinate(rng), coordinate(rng)};
    std::vector<Triangle> triangles(1500);
    for (Triangle& t : triangles) t = {pick(rng), pick(rng), pick(rng)};
    const compress::ColorNeighbourhood nb =
        compress::color_neighbourhood(compress::vertex_adjacency(vertices, triangles), grid);
    for (std::uint32_t i = 0; i < vertices; ++i) {
      const auto d2 = [&](std::uint32_t v) {
        std::uint64_t d = 0;
        for (std::size_t a = 0; a < 3; ++a) {
          const std::int64_t t = std::int64_t{grid[v][a]} - grid[i][a];
          d += static_cast<std::uint64_t>(t * t);
        }
        return d;
      };
      std::uint32_t end = nb.adj.first[i];
      std::uint64_t nearest = ~std::uint64_t{0};
      for (; end < nb.adj.first[i + 1] && nb.adj.neighbour[end] < i; ++end)
        nearest = std::min(nearest, d2(nb.adj.neighbour[end]));
      ASSERT_EQ(nb.decoded_end[i], end) << i;
      for (std::uint32_t k = nb.adj.first[i]; k < end; ++k) {
        const std::uint64_t r = ((nearest + 1) << 16) / (d2(nb.adj.neighbour[k]) + 1);
        EXPECT_EQ(nb.weight[k], (r * r) >> 16) << i << " " << k << " spread " << spread;
      }
      if (end > nb.adj.first[i]) {
        EXPECT_EQ(nb.distance_bits[i], 64 - __builtin_clzll(nearest + 1)) << i;
      }
    }
  }
}

// Both jobs run; the first's error wins over the second's, the second's comes out alone.
TEST(SideBySide, BothRunAndTheFirstErrorWins) {
  int ran = 0;
  compress::side_by_side([&] { ran += 1; }, [&] { ran += 2; });
  EXPECT_EQ(ran, 3);
  const auto message = [](auto first, auto second) {
    try {
      compress::side_by_side(first, second);
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("none");
  };
  const auto one = [] { throw std::runtime_error("one"); };
  const auto two = [] { throw std::runtime_error("two"); };
  const auto fine = [] {};
  EXPECT_EQ(message(one, two), "one");
  EXPECT_EQ(message(fine, two), "two");
  EXPECT_EQ(message(one, fine), "one");
  EXPECT_EQ(message(fine, fine), "none");
}

}  // namespace
}  // namespace meshflow
