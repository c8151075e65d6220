#include "runtime/vertex_triangles.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <numeric>

#include "runtime/default_init.h"
#include "runtime/parallel.h"

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
  UninitVector<std::uint32_t> slots(chunks * vertex_count);  // each row zeroed by its chunk
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
    std::uint32_t* count = slots.data() + c * vertex_count;
    std::fill(count, count + vertex_count, 0u);
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

// Union-find over slots with path halving whose roots are the lowest slot of their set.
struct SlotSets {
  std::uint32_t* parent;
  std::uint32_t find(std::uint32_t x) const {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(std::uint32_t a, std::uint32_t b) const {
    a = find(a);
    b = find(b);
    parent[std::max(a, b)] = std::min(a, b);
  }
};

// Numbers the sets: fan[i] = the set of slot i (0 = the set of slot 0, then in order of their
// lowest slots; a root is its set's lowest slot, so slots in order meet each root before its
// other members). Returns the set count.
std::uint32_t number_fans(const SlotSets& sets, std::uint32_t k, std::uint32_t* fan) {
  std::uint32_t fans = 0;
  for (std::uint32_t i = 0; i < k; ++i) {
    const std::uint32_t r = sets.find(i);
    fan[i] = r == i ? fans++ : fan[r];
  }
  return fans;
}

// Whether the k (1 to 16) triangles around v form one consistently oriented fan: walking from the
// first triangle along its out-spoke (the corner after v), each step to the triangle whose
// in-spoke (the corner before v) it is, then backwards the same way, reaches all k. Visited
// triangles share spokes, so reaching all of them proves one fan; false says nothing (several
// fans, or orientations that disagree: the caller decides pairwise). O(k^2) comparisons.
bool one_oriented_fan(const std::vector<Triangle>& triangles, std::uint32_t v,
                      std::size_t vertex_count, const std::uint32_t* begin, std::uint32_t k) {
  std::uint32_t in[16], out[16];
  for (std::uint32_t i = 0; i < k; ++i) {
    const Triangle& t = triangles[begin[i]];
    const int r = t[0] == v ? 0 : t[1] == v ? 1 : 2;
    out[i] = t[(r + 1) % 3];
    in[i] = t[(r + 2) % 3];
    if (out[i] == v || in[i] == v || out[i] >= vertex_count || in[i] >= vertex_count)
      return false;  // (a corner repeated, or past the vertices: decided pairwise)
  }
  std::uint32_t visited = 1, reached = 1;
  // Forward from triangle 0, then backward from it; each step looks for an unvisited neighbour.
  for (int direction = 0; direction < 2; ++direction) {
    for (std::uint32_t at = 0;;) {
      const std::uint32_t spoke = direction == 0 ? out[at] : in[at];
      const std::uint32_t* ends = direction == 0 ? in : out;
      std::uint32_t next = k;
      for (std::uint32_t j = 0; j < k; ++j)
        if (ends[j] == spoke && (visited >> j & 1u) == 0) {
          next = j;
          break;
        }
      if (next == k) break;
      visited |= 1u << next;
      ++reached;
      at = next;
    }
  }
  return reached == k;
}

// Fans of a vertex with few triangles (every pixel-grid vertex, most vertices of any mesh): one
// oriented fan confirmed by a walk (the common case), else each pair of triangles compared by
// their spokes, on the stack. O(k^2).
constexpr std::uint32_t kFewTriangles = 16;
std::uint32_t fans_around_few(const std::vector<Triangle>& triangles, std::uint32_t v,
                              std::size_t vertex_count, const std::uint32_t* begin, std::uint32_t k,
                              std::uint32_t* fan) {
  if (k == 0) return 0;
  if (one_oriented_fan(triangles, v, vertex_count, begin, k)) {
    std::fill(fan, fan + k, 0u);
    return 1;
  }
  std::uint32_t spokes[kFewTriangles][2], parent[kFewTriangles];
  for (std::uint32_t i = 0; i < k; ++i) {
    parent[i] = i;
    std::uint32_t n = 0;
    spokes[i][0] = spokes[i][1] = UINT32_MAX;  // (no spoke: matches nothing below)
    for (std::uint32_t x : triangles[begin[i]])
      if (x != v && x < vertex_count && n < 2) spokes[i][n++] = x;
  }
  const SlotSets sets{parent};
  for (std::uint32_t i = 1; i < k; ++i)
    for (std::uint32_t j = 0; j < i; ++j)
      for (std::uint32_t x : spokes[i])
        if (x != UINT32_MAX && (x == spokes[j][0] || x == spokes[j][1])) sets.unite(i, j);
  return number_fans(sets, k, fan);
}

// Writes the fan of each triangle around v to fan[0 .. k) (0 = the fan with the lowest triangle
// index, then in order of their lowest triangles), given the k triangles around v in ascending
// order and `vertex_count` vertices. Triangles sharing an edge v-x (a corner x other than v) are
// in one fan. Few triangles go through fans_around_few(); more go through a spoke table: each spoke
// x joins the triangle holding it to the previous one that did. Returns the fan count. O(k^2) for
// k <= 16, else O(k) with O(vertex_count) scratch (allocated on first use).
std::uint32_t fans_around(const std::vector<Triangle>& triangles, std::uint32_t v,
                          std::size_t vertex_count, const std::uint32_t* begin,
                          const std::uint32_t* end, std::uint32_t* fan, FanScratch& scratch) {
  const auto k = static_cast<std::uint32_t>(end - begin);
  if (k <= kFewTriangles) return fans_around_few(triangles, v, vertex_count, begin, k, fan);
  auto& spokes = scratch.spokes;
  if (spokes.size() != vertex_count) spokes.assign(vertex_count, FanScratch::Spoke{});
  scratch.parent.resize(k);
  std::iota(scratch.parent.begin(), scratch.parent.end(), 0u);
  const SlotSets sets{scratch.parent.data()};
  for (std::uint32_t i = 0; i < k; ++i)
    for (std::uint32_t x : triangles[begin[i]]) {
      if (x == v || x >= vertex_count) continue;  // (an index past the vertices: no spoke)
      FanScratch::Spoke& spoke = spokes[x];
      if (spoke.vertex == v) sets.unite(i, spoke.slot);  // the previous triangle holding x
      spoke = {v, i};
    }
  return number_fans(sets, k, fan);
}

}  // namespace

std::vector<std::uint32_t> vertex_fans(const std::vector<Triangle>& triangles,
                                       const VertexTriangles& around,
                                       std::vector<std::uint32_t>& fan) {
  const std::size_t n = around.offsets.size() - 1;
  fan.resize(around.triangles.size());
  std::vector<std::uint32_t> fans(n, 0);
  tbb::enumerable_thread_specific<FanScratch> scratch_per_thread;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      FanScratch& scratch = scratch_per_thread.local();
                      for (std::size_t i = range.begin(); i != range.end(); ++i) {
                        const auto v = static_cast<std::uint32_t>(i);
                        fans[i] = fans_around(triangles, v, n, around.begin(v), around.end(v),
                                              fan.data() + around.offsets[v], scratch);
                      }
                    });
  return fans;
}

namespace {

// The vertices whose triangles form more than one fan, ascending. Parallel per vertex (a fan
// count each; the fan of every triangle is not kept: few vertices need it); deterministic. O(V+T).
std::vector<std::uint32_t> vertices_with_several_fans(const std::vector<Triangle>& triangles,
                                                      const VertexTriangles& around) {
  const std::size_t n = around.offsets.size() - 1;
  std::vector<std::uint8_t> several(n, 0);
  struct Scratch {
    FanScratch fans;
    std::vector<std::uint32_t> fan;
  };
  tbb::enumerable_thread_specific<Scratch> scratch_per_thread;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      Scratch& scratch = scratch_per_thread.local();
                      for (std::size_t i = range.begin(); i != range.end(); ++i) {
                        const auto v = static_cast<std::uint32_t>(i);
                        scratch.fan.resize(around.offsets[v + 1] - around.offsets[v]);
                        several[i] = fans_around(triangles, v, n, around.begin(v), around.end(v),
                                                 scratch.fan.data(), scratch.fans) > 1;
                      }
                    });
  return parallel_select_indices(n, [&several](std::size_t v) { return several[v] != 0; });
}

}  // namespace

void remove_smaller_fans(std::vector<Triangle>& triangles, std::size_t vertex_count,
                         FanRemovalCounts* counts, const std::vector<std::uint8_t>* held) {
  const auto is_held = [held](std::uint32_t v) {
    return held != nullptr && v < held->size() && (*held)[v] != 0;
  };
  FanRemovalCounts c;
  // The first pass looks at the vertices with several fans (found in parallel); a later one at
  // the corners of the triangles the pass before removed, the only vertices whose fans can have
  // changed.
  const VertexTriangles around = vertex_triangles(triangles, vertex_count);
  std::vector<std::uint32_t> candidates = vertices_with_several_fans(triangles, around);
  std::vector<std::uint8_t> removed(candidates.empty() ? 0 : triangles.size(), 0);
  FanScratch scratch;
  std::vector<std::uint32_t> alive, fan_of, size, marks;
  while (!candidates.empty()) {
    // Each candidate decides on the mesh as the pass found it (marks are applied afterwards),
    // in vertex order, serially: nothing depends on the thread count.
    marks.clear();
    for (const std::uint32_t v : candidates) {
      if (is_held(v)) continue;
      alive.clear();
      for (const std::uint32_t* t = around.begin(v); t != around.end(v); ++t)
        if (removed[*t] == 0) alive.push_back(*t);
      const auto k = static_cast<std::uint32_t>(alive.size());
      fan_of.resize(k);
      const std::uint32_t fans = fans_around(triangles, v, vertex_count, alive.data(),
                                             alive.data() + k, fan_of.data(), scratch);
      if (fans < 2) continue;
      ++c.vertices;
      size.assign(fans, 0);
      for (std::uint32_t s = 0; s < k; ++s) ++size[fan_of[s]];
      // The largest fan stays; of equal ones the lowest-numbered (holding the lowest triangle).
      const auto keep =
          static_cast<std::uint32_t>(std::max_element(size.begin(), size.end()) - size.begin());
      for (std::uint32_t s = 0; s < k; ++s)
        if (fan_of[s] != keep) marks.push_back(alive[s]);
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
