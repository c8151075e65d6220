#include "nodes/compress/closed_surface.h"

#include <algorithm>
#include <memory>

namespace meshflow::compress {
namespace {

// Pairs the half-edges of edges used by exactly two faces in opposite directions: half-edges
// listed by origin with their ends beside them (a counting sort); per origin a, how many a -> b
// there are for each end b (a counter per vertex, cleared after a); then each single a -> b
// looks for b -> a among b's, reading one short run of the list. O(T x valence).
void pair_twins(const std::vector<std::uint32_t>& corners, std::size_t vertices,
                std::vector<std::uint32_t>& twin) {
  const auto halves = static_cast<std::uint32_t>(corners.size());
  std::vector<std::uint32_t> first(vertices + 1, 0);
  // Every entry of these is written below: no clearing.
  const std::unique_ptr<std::uint32_t[]> by_origin(new std::uint32_t[halves]),
      end(new std::uint32_t[halves]);
  const std::unique_ptr<std::uint8_t[]> single(new std::uint8_t[halves]);
  for (std::uint32_t v : corners) ++first[v + 1];
  for (std::size_t v = 0; v < vertices; ++v) first[v + 1] += first[v];
  {
    std::vector<std::uint32_t> fill(first.begin(), first.end() - 1);
    for (std::uint32_t t = 0; t < halves; t += 3)
      for (std::uint32_t j = 0; j < 3; ++j) {
        const std::uint32_t i = fill[corners[t + j]]++;
        by_origin[i] = t + j;
        end[i] = corners[t + (j == 2 ? 0 : j + 1)];
      }
  }
  // single[i]: list entry i is its origin's only half-edge to its end.
  {
    std::vector<std::uint32_t> count(vertices, 0);
    for (std::uint32_t a = 0; a < vertices; ++a) {
      for (std::uint32_t j = first[a]; j < first[a + 1]; ++j) ++count[end[j]];
      for (std::uint32_t j = first[a]; j < first[a + 1]; ++j) single[j] = count[end[j]] == 1;
      for (std::uint32_t j = first[a]; j < first[a + 1]; ++j) count[end[j]] = 0;
    }
  }
  twin.assign(halves, kNone);
  for (std::uint32_t a = 0; a < vertices; ++a)
    for (std::uint32_t j = first[a]; j < first[a + 1]; ++j) {
      const std::uint32_t h = by_origin[j];
      if (twin[h] != kNone || !single[j]) continue;
      const std::uint32_t b = end[j];
      std::uint32_t reverse = kNone, reverse_count = 0;
      for (std::uint32_t i = first[b]; i < first[b + 1]; ++i)
        if (end[i] == a) {
          reverse = by_origin[i];
          ++reverse_count;
        }
      if (reverse_count == 1) {
        twin[h] = reverse;
        twin[reverse] = h;
      }
    }
}

}  // namespace

ClosedSurface build_closed_surface(const std::vector<Triangle>& triangles) {
  ClosedSurface s;
  std::vector<std::uint32_t> input_corners(3 * triangles.size());  // input vertex per corner
  s.input_triangle.reserve(triangles.size());
  std::size_t kept = 0;
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    const Triangle& f = triangles[t];
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) {
      s.degenerate_triangles.push_back(t);
      continue;
    }
    for (std::size_t j = 0; j < 3; ++j) input_corners[3 * kept + j] = f[j];
    ++kept;
    s.input_triangle.push_back(t);
  }
  input_corners.resize(3 * kept);
  std::size_t vertices = 0;
  for (std::uint32_t v : input_corners) vertices = std::max<std::size_t>(vertices, v + 1);
  pair_twins(input_corners, vertices, s.twin);

  // Fans: the corners around a vertex joined across shared edges. Around origin v, the corner
  // after h is next(twin(h)), the one before twin(prev(h)); each fan is walked from its first
  // corner (after a cut) or, if closed, from the corner met first.
  const auto corners = static_cast<std::uint32_t>(input_corners.size());
  s.corner_vertex.assign(corners, kNone);
  for (std::uint32_t h = 0; h < corners; ++h) {
    if (s.corner_vertex[h] != kNone) continue;
    std::uint32_t start = h;
    for (std::uint32_t before = s.twin[prev_half(start)]; before != kNone && before != h;
         before = s.twin[prev_half(start)])
      start = before;
    const auto fan = static_cast<std::uint32_t>(s.input_vertex.size());
    s.input_vertex.push_back(input_corners[h]);
    for (std::uint32_t c = start; c != kNone && s.corner_vertex[c] == kNone;
         c = s.twin[c] == kNone ? kNone : next_half(s.twin[c]))
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
