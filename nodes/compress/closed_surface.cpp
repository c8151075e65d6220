#include "nodes/compress/closed_surface.h"

#include <algorithm>

#include "runtime/disjoint_sets.h"

namespace meshflow::compress {
namespace {

// Pairs the half-edges of edges used by exactly two faces in opposite directions.
void pair_twins(const std::vector<std::uint32_t>& corners, std::vector<std::uint32_t>& twin) {
  struct Directed {
    std::uint64_t key;   // the undirected edge
    std::uint32_t half;  // the half-edge
    bool forward;        // origin < destination
  };
  std::vector<Directed> edges(corners.size());
  for (std::uint32_t h = 0; h < corners.size(); ++h) {
    const std::uint32_t a = corners[h], b = corners[next_half(h)];
    edges[h] = {undirected_edge_key(a, b), h, a < b};
  }
  std::sort(edges.begin(), edges.end(), [](const Directed& x, const Directed& y) {
    return x.key != y.key ? x.key < y.key : x.half < y.half;
  });
  twin.assign(corners.size(), kNone);
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i + 1;
    while (j < edges.size() && edges[j].key == edges[i].key) ++j;
    if (j - i == 2 && edges[i].forward != edges[i + 1].forward) {
      twin[edges[i].half] = edges[i + 1].half;
      twin[edges[i + 1].half] = edges[i].half;
    }
    i = j;
  }
}

}  // namespace

ClosedSurface build_closed_surface(const std::vector<Triangle>& triangles) {
  ClosedSurface s;
  std::vector<std::uint32_t> input_corners;  // input vertex per corner
  input_corners.reserve(3 * triangles.size());
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    const Triangle& f = triangles[t];
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) {
      s.degenerate_triangles.push_back(t);
      continue;
    }
    input_corners.insert(input_corners.end(), f.begin(), f.end());
    s.input_triangle.push_back(t);
  }
  pair_twins(input_corners, s.twin);

  // Fans: corners joined across shared edges (corner h and the corner of its origin in the
  // triangle across h's edge).
  const auto corners = static_cast<std::uint32_t>(input_corners.size());
  DisjointSets fans(corners);
  for (std::uint32_t h = 0; h < corners; ++h)
    if (s.twin[h] != kNone) fans.unite(h, next_half(s.twin[h]));
  std::vector<std::uint32_t> fan_of_root(corners, kNone);
  s.corner_vertex.resize(corners);
  for (std::uint32_t h = 0; h < corners; ++h) {
    std::uint32_t& fan = fan_of_root[fans.find(h)];
    if (fan == kNone) {
      fan = static_cast<std::uint32_t>(s.input_vertex.size());
      s.input_vertex.push_back(input_corners[h]);
    }
    s.corner_vertex[h] = fan;
  }

  // Each fan with a cut has one cut half-edge leaving it and one entering it; a hole loop
  // walks from a cut half-edge to the cut half-edge entering its origin.
  std::vector<std::uint32_t> entering(s.input_vertex.size(), kNone);
  for (std::uint32_t h = 0; h < corners; ++h)
    if (s.twin[h] == kNone) entering[s.corner_vertex[next_half(h)]] = h;
  std::vector<std::uint8_t> closed(corners, 0);
  for (std::uint32_t start = 0; start < corners; ++start) {
    if (s.twin[start] != kNone || closed[start]) continue;
    const auto hole = static_cast<std::uint32_t>(s.input_vertex.size());
    s.input_vertex.push_back(kNone);
    ++s.hole_count;
    // The fan triangle of cut half-edge h (a -> b) is (b, a, hole): its half-edge b -> a is h's
    // twin, a -> hole the twin of the hole -> a of the triangle of the cut edge entering a.
    std::vector<std::uint32_t> loop;
    for (std::uint32_t h = start; !closed[h]; h = entering[s.corner_vertex[h]]) {
      closed[h] = 1;
      loop.push_back(h);
    }
    const auto first = static_cast<std::uint32_t>(s.corner_vertex.size());
    const auto n = static_cast<std::uint32_t>(loop.size());
    for (std::uint32_t k = 0; k < n; ++k) {
      const std::uint32_t h = loop[k];
      const std::uint32_t f =
          first + 3 * k;  // half-edges f: b -> a, f+1: a -> hole, f+2: hole -> b
      s.corner_vertex.push_back(s.corner_vertex[next_half(h)]);
      s.corner_vertex.push_back(s.corner_vertex[h]);
      s.corner_vertex.push_back(hole);
      s.input_triangle.push_back(kNone);
      s.twin.push_back(h);
      s.twin[h] = f;
      // a -> hole pairs with hole -> a of the next loop entry (the cut edge entering a).
      const std::uint32_t g = first + 3 * ((k + 1) % n);
      s.twin.push_back(g + 2);
      s.twin.push_back(first + 3 * ((k + n - 1) % n) + 1);
    }
  }
  return s;
}

}  // namespace meshflow::compress
