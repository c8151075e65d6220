#include "runtime/vertex_triangles.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <numeric>

namespace meshflow {

VertexTriangles vertex_triangles(const TriangleMesh& mesh) {
  return vertex_triangles(mesh.triangles, mesh.vertices.size());
}

VertexTriangles vertex_triangles(const std::vector<Triangle>& tris, std::size_t vertex_count) {
  VertexTriangles out;
  out.offsets.assign(vertex_count + 1, 0);
  out.triangles.resize(tris.size() * 3);
  // Consecutive triangle chunks, one per worker: chunk c counts its corners per vertex in its
  // own row of `slots` (later: where its next triangle goes in each vertex's row). A vertex's
  // row lists chunk 0's triangles, then chunk 1's, ..., each in order: ascending for any
  // chunking. At most 8 chunks, and no more than 3 T / V of them, so that the rows of `slots`
  // (V each) take no more memory than the output's 3 T entries.
  constexpr std::size_t kMinTrianglesPerChunk = 8192, kMaxChunks = 8;
  const std::size_t most =
      std::min({kMaxChunks, 3 * tris.size() / std::max<std::size_t>(vertex_count, 1),
                static_cast<std::size_t>(tbb::this_task_arena::max_concurrency())});
  const std::size_t chunks =
      std::max<std::size_t>(1, std::min(tris.size() / kMinTrianglesPerChunk, most));
  const auto chunk_begin = [&](std::size_t c) { return tris.size() * c / chunks; };
  std::vector<std::uint32_t> slots(chunks * vertex_count, 0);
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
    std::uint32_t* count = slots.data() + c * vertex_count;
    for (std::size_t t = chunk_begin(c); t < chunk_begin(c + 1); ++t)
      for (std::uint32_t v : tris[t])
        if (v < vertex_count) ++count[v];  // (an index past the vertices is not listed)
  });
  // Row starts (a two-level scan over vertex ranges), and every chunk's start within each row.
  constexpr std::size_t kMinVerticesPerRange = 16384;
  const std::size_t ranges =
      std::clamp<std::size_t>(vertex_count / kMinVerticesPerRange, 1,
                              static_cast<std::size_t>(tbb::this_task_arena::max_concurrency()));
  const auto range_begin = [&](std::size_t r) { return vertex_count * r / ranges; };
  std::vector<std::uint32_t> range_base(ranges + 1, 0);
  tbb::parallel_for(std::size_t{0}, ranges, [&](std::size_t r) {
    std::uint32_t sum = 0;
    for (std::size_t c = 0; c < chunks; ++c) {
      const std::uint32_t* count = slots.data() + c * vertex_count;
      for (std::size_t v = range_begin(r); v < range_begin(r + 1); ++v) sum += count[v];
    }
    range_base[r + 1] = sum;
  });
  for (std::size_t r = 0; r < ranges; ++r) range_base[r + 1] += range_base[r];
  tbb::parallel_for(std::size_t{0}, ranges, [&](std::size_t r) {
    std::uint32_t at = range_base[r];
    for (std::size_t v = range_begin(r); v < range_begin(r + 1); ++v) {
      out.offsets[v] = at;
      for (std::size_t c = 0; c < chunks; ++c) {
        std::uint32_t& slot = slots[c * vertex_count + v];
        const std::uint32_t length = slot;
        slot = at;
        at += length;
      }
    }
  });
  out.offsets[vertex_count] = range_base[ranges];
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
    std::uint32_t* next = slots.data() + c * vertex_count;
    for (std::size_t t = chunk_begin(c); t < chunk_begin(c + 1); ++t)
      for (std::uint32_t v : tris[t])
        if (v < vertex_count) out.triangles[next[v]++] = static_cast<std::uint32_t>(t);
  });
  out.triangles.resize(out.offsets[vertex_count]);
  return out;
}

namespace {

// The working memory of fans_around(), reused from vertex to vertex by one thread.
struct FanScratch {
  /// Per vertex x: the vertex v whose fans were last looked at with x as a spoke, and the slot of
  /// the latest of v's triangles holding x (stamped with v: nothing is cleared between vertices).
  struct Spoke {
    std::uint32_t vertex = UINT32_MAX, slot = 0;
  };
  std::vector<Spoke> spokes;
  std::vector<std::uint32_t> parent;  ///< union-find over the slots of v's triangles
};

// Writes the fan of each triangle around v to fan[0 .. k) (0 = the fan with the lowest triangle
// index, then in order of their lowest triangles), given the k triangles around v in ascending
// order. Triangles sharing an edge v-x (a corner x other than v) are in one fan: each spoke x
// joins the triangle holding it to the previous one that did. Returns the fan count. O(k).
std::uint32_t fans_around(const std::vector<Triangle>& triangles, std::uint32_t v,
                          const std::uint32_t* begin, const std::uint32_t* end, std::uint32_t* fan,
                          FanScratch& scratch) {
  const auto k = static_cast<std::uint32_t>(end - begin);
  auto& spokes = scratch.spokes;
  auto& parent = scratch.parent;  // (a reference, not a structured binding: lambdas capture it)
  parent.resize(k);
  std::iota(parent.begin(), parent.end(), 0u);
  // Union-find with path halving whose roots are the lowest slot of their set.
  const auto find = [&parent](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (std::uint32_t i = 0; i < k; ++i)
    for (std::uint32_t x : triangles[begin[i]]) {
      if (x == v || x >= spokes.size()) continue;  // (an index past the vertices: no spoke)
      FanScratch::Spoke& spoke = spokes[x];
      if (spoke.vertex == v) {  // joined with the previous of v's triangles holding x
        const std::uint32_t a = find(i), b = find(spoke.slot);
        parent[std::max(a, b)] = std::min(a, b);
      }
      spoke = {v, i};
    }
  // A root is its fan's lowest slot, so slots in order meet each root before its other members.
  std::uint32_t fans = 0;
  for (std::uint32_t i = 0; i < k; ++i) {
    const std::uint32_t r = find(i);
    fan[i] = r == i ? fans++ : fan[r];
  }
  return fans;
}

}  // namespace

std::vector<std::uint32_t> vertex_fans(const std::vector<Triangle>& triangles,
                                       const VertexTriangles& around,
                                       std::vector<std::uint32_t>& fan) {
  const std::size_t n = around.offsets.size() - 1;
  fan.resize(around.triangles.size());
  std::vector<std::uint32_t> fans(n, 0);
  tbb::enumerable_thread_specific<FanScratch> scratch_per_thread([n] {
    FanScratch scratch;
    scratch.spokes.resize(n);
    return scratch;
  });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      FanScratch& scratch = scratch_per_thread.local();
                      for (std::size_t i = range.begin(); i != range.end(); ++i) {
                        const auto v = static_cast<std::uint32_t>(i);
                        fans[i] = fans_around(triangles, v, around.begin(v), around.end(v),
                                              fan.data() + around.offsets[v], scratch);
                      }
                    });
  return fans;
}

void remove_smaller_fans(std::vector<Triangle>& triangles, std::size_t vertex_count,
                         FanRemovalCounts* counts) {
  FanRemovalCounts c;
  // The first pass looks at every vertex (in parallel); a later one only at the corners of the
  // triangles the pass before removed, the only vertices whose fans can have changed.
  const VertexTriangles around = vertex_triangles(triangles, vertex_count);
  std::vector<std::uint32_t> fan;
  const std::vector<std::uint32_t> first_fans = vertex_fans(triangles, around, fan);
  std::vector<std::uint32_t> candidates;
  for (std::uint32_t v = 0; v < vertex_count; ++v)
    if (first_fans[v] > 1) candidates.push_back(v);
  std::vector<std::uint8_t> removed(triangles.size(), 0);
  FanScratch scratch;
  std::vector<std::uint32_t> alive, alive_fan, size, marks;
  for (bool first_pass = true; !candidates.empty(); first_pass = false) {
    // Each candidate decides on the mesh as the pass found it (marks are applied afterwards),
    // in vertex order, serially: nothing depends on the thread count.
    marks.clear();
    for (const std::uint32_t v : candidates) {
      const std::uint32_t* slots = around.begin(v);
      const std::uint32_t* fan_of = fan.data() + around.offsets[v];
      std::uint32_t k = static_cast<std::uint32_t>(around.end(v) - slots), fans = first_fans[v];
      if (!first_pass) {
        alive.clear();
        for (const std::uint32_t* t = slots; t != around.end(v); ++t)
          if (removed[*t] == 0) alive.push_back(*t);
        k = static_cast<std::uint32_t>(alive.size());
        alive_fan.resize(k);
        if (scratch.spokes.size() != vertex_count) scratch.spokes.resize(vertex_count);
        fans = fans_around(triangles, v, alive.data(), alive.data() + k, alive_fan.data(), scratch);
        slots = alive.data();
        fan_of = alive_fan.data();
      }
      if (fans < 2) continue;
      ++c.vertices;
      size.assign(fans, 0);
      for (std::uint32_t s = 0; s < k; ++s) ++size[fan_of[s]];
      // The largest fan stays; of equal ones the lowest-numbered (holding the lowest triangle).
      const auto keep =
          static_cast<std::uint32_t>(std::max_element(size.begin(), size.end()) - size.begin());
      for (std::uint32_t s = 0; s < k; ++s)
        if (fan_of[s] != keep) marks.push_back(slots[s]);
    }
    candidates.clear();
    for (const std::uint32_t t : marks) {
      if (removed[t] != 0) continue;  // (marked by two vertices)
      removed[t] = 1;
      ++c.triangles;
      for (const std::uint32_t x : triangles[t])
        if (x < vertex_count) candidates.push_back(x);
    }
    if (candidates.empty()) break;
    ++c.passes;
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
  }
  if (c.triangles > 0) {
    std::size_t kept = 0;
    for (std::size_t t = 0; t < triangles.size(); ++t)
      if (removed[t] == 0) triangles[kept++] = triangles[t];
    triangles.resize(kept);
  }
  if (counts != nullptr) {
    counts->vertices += c.vertices;
    counts->triangles += c.triangles;
    counts->passes += c.passes;
  }
}

}  // namespace meshflow
