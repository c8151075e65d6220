#include "nodes/compress/closed_surface.h"

#include <algorithm>
#include <memory>

namespace meshflow::compress {
namespace {

// Pairs the half-edges of edges used by exactly two faces in opposite directions: half-edges
// listed by origin with their ends beside them (a counting sort); per origin a, how many a -> b
// there are for each end b (a counter per vertex, cleared after a); then each single a -> b with
// b > a looks for b -> a among b's, reading one short run of the list (an edge b -> a with b < a
// was tried from b: the pairing asks the same of both sides). O(T x valence).
void pair_twins(const std::vector<std::uint32_t>& corners, std::size_t vertices,
                std::vector<std::uint32_t>& twin) {
  const auto halves = static_cast<std::uint32_t>(corners.size());
  std::vector<std::uint32_t> first(vertices + 1, 0);
  // Every entry of these is written below: no clearing.
  const std::unique_ptr<std::uint32_t[]> by_origin(new std::uint32_t[halves]),
      end(new std::uint32_t[halves]);
  for (std::uint32_t v : corners) ++first[v + 1];
  for (std::size_t v = 0; v < vertices; ++v) first[v + 1] += first[v];
  {
    std::vector<std::uint32_t> fill(first.begin(), first.end() - 1);
    for (std::uint32_t t = 0; t < halves; t += 3) {
      const std::uint32_t c0 = corners[t], c1 = corners[t + 1], c2 = corners[t + 2];
      std::uint32_t i = fill[c0]++;
      by_origin[i] = t;
      end[i] = c1;
      i = fill[c1]++;
      by_origin[i] = t + 1;
      end[i] = c2;
      i = fill[c2]++;
      by_origin[i] = t + 2;
      end[i] = c0;
    }
  }
  twin.assign(halves, kNone);
  std::vector<std::uint32_t> count(vertices, 0);
  for (std::uint32_t a = 0; a < vertices; ++a) {
    const std::uint32_t begin = first[a], stop = first[a + 1];
    for (std::uint32_t j = begin; j < stop; ++j) ++count[end[j]];
    for (std::uint32_t j = begin; j < stop; ++j) {
      const std::uint32_t b = end[j];
      if (b < a || count[b] != 1) continue;
      std::uint32_t reverse = kNone, reverse_count = 0;
      for (std::uint32_t i = first[b]; i < first[b + 1]; ++i)
        if (end[i] == a) {
          reverse = by_origin[i];
          ++reverse_count;
        }
      if (reverse_count == 1) {
        twin[by_origin[j]] = reverse;
        twin[reverse] = by_origin[j];
      }
    }
    for (std::uint32_t j = begin; j < stop; ++j) count[end[j]] = 0;
  }
}

}  // namespace

ClosedSurface build_closed_surface(const std::vector<Triangle>& triangles) {
  ClosedSurface s;
  std::vector<std::uint32_t> input_corners(3 * triangles.size());  // input vertex per corner
  s.input_triangle.reserve(triangles.size());
  std::size_t kept = 0;
  std::uint32_t largest = 0;  // the largest corner kept
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    const Triangle& f = triangles[t];
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) {
      s.degenerate_triangles.push_back(t);
      continue;
    }
    for (std::size_t j = 0; j < 3; ++j) input_corners[3 * kept + j] = f[j];
    largest = std::max({largest, f[0], f[1], f[2]});
    ++kept;
    s.input_triangle.push_back(t);
  }
  input_corners.resize(3 * kept);
  const std::size_t vertices = kept == 0 ? 0 : std::size_t{largest} + 1;
  pair_twins(input_corners, vertices, s.twin);

  // Fans: the corners around a vertex joined across shared edges. Around origin v, the corner
  // after h is next(twin(h)), the one before twin(prev(h)) (each step the other's inverse: a
  // fan is a cycle or a path). Each fan is walked from the corner met first: forward to its
  // end or round to that corner again, then, if it ended at a cut, backward to its start.
  const auto corners = static_cast<std::uint32_t>(input_corners.size());
  s.corner_vertex.assign(corners, kNone);
  for (std::uint32_t h = 0; h < corners; ++h) {
    if (s.corner_vertex[h] != kNone) continue;
    const auto fan = static_cast<std::uint32_t>(s.input_vertex.size());
    s.input_vertex.push_back(input_corners[h]);
    for (std::uint32_t c = h; c != kNone && s.corner_vertex[c] == kNone;
         c = s.twin[c] == kNone ? kNone : next_half(s.twin[c]))
      s.corner_vertex[c] = fan;
    for (std::uint32_t c = s.twin[prev_half(h)]; c != kNone && s.corner_vertex[c] == kNone;
         c = s.twin[prev_half(c)])
      s.corner_vertex[c] = fan;
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
