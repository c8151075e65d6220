#include "runtime/vertex_triangles.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>

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

}  // namespace meshflow
