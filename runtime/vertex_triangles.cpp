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
  constexpr std::size_t kMinVerticesPerRange = 4096;
  const std::size_t ranges =
      std::clamp<std::size_t>(vertex_count / kMinVerticesPerRange, 1,
                              static_cast<std::size_t>(tbb::this_task_arena::max_concurrency()));
  auto range_begin = [&](std::size_t r) {
    return static_cast<std::uint32_t>(vertex_count * r / ranges);
  };
  // Row lengths (in offsets[v] for now), and each range's total.
  std::vector<std::uint32_t> range_totals(ranges, 0);
  tbb::parallel_for(std::size_t{0}, ranges, [&](std::size_t r) {
    const std::uint32_t lo = range_begin(r), hi = range_begin(r + 1);
    for (const Triangle& t : tris)
      for (std::uint32_t v : t)
        if (v >= lo && v < hi) ++out.offsets[v];
    std::uint32_t sum = 0;
    for (std::uint32_t v = lo; v < hi; ++v) sum += out.offsets[v];
    range_totals[r] = sum;
  });
  std::uint32_t base = 0;
  for (std::size_t r = 0; r < ranges; ++r) {
    const std::uint32_t total = range_totals[r];
    range_totals[r] = base;
    base += total;
  }
  tbb::parallel_for(std::size_t{0}, ranges, [&](std::size_t r) {
    const std::uint32_t lo = range_begin(r), hi = range_begin(r + 1);
    // Row length -> row start: the range's base plus the lengths of the rows before it.
    std::uint32_t at = range_totals[r];
    for (std::uint32_t v = lo; v < hi; ++v) {
      const std::uint32_t length = out.offsets[v];
      out.offsets[v] = at;
      at += length;
    }
  });
  out.offsets[vertex_count] = base;
  tbb::parallel_for(std::size_t{0}, ranges, [&](std::size_t r) {
    const std::uint32_t lo = range_begin(r), hi = range_begin(r + 1);
    std::vector<std::uint32_t> cursor(out.offsets.begin() + lo, out.offsets.begin() + hi);
    for (std::uint32_t t = 0; t < tris.size(); ++t)
      for (std::uint32_t v : tris[t])
        if (v >= lo && v < hi) out.triangles[cursor[v - lo]++] = t;
  });
  return out;
}

}  // namespace meshflow
