#include "nodes/extract/marching_cubes.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <memory>

#include "nodes/extract/cube_table.h"
#include "runtime/parallel.h"

namespace meshflow {
namespace {

// Grid edges are numbered lower corner index * 3 + axis.
std::size_t edge_key(const std::array<std::uint32_t, 8>& corners, int e) {
  return static_cast<std::size_t>(
             corners[static_cast<std::size_t>(kCubeEdges[static_cast<std::size_t>(e)][0])]) *
             3 +
         static_cast<std::size_t>(kCubeEdgeAxis[static_cast<std::size_t>(e)]);
}

constexpr std::uint32_t kNoEdge = UINT32_MAX;

// Calls f(local edge e, its two corners) for every edge of case `pattern` that crosses the surface.
template <typename F>
void for_each_crossed_edge(int pattern, F f) {
  for (int e = 0; e < 12; ++e) {
    const auto& ce = kCubeEdges[static_cast<std::size_t>(e)];
    if (((pattern >> ce[0]) & 1) != ((pattern >> ce[1]) & 1)) f(e, ce[0], ce[1]);
  }
}

}  // namespace

TriangleMesh marching_cubes(const SparseGrid& grid, const DistanceField& field,
                            const ExtractConfig& config) {
  const auto& cases = cube_cases();
  const std::size_t cells = grid.cells.size();

  // 1. Case of every cell (0 = nothing to extract, including cells with an invalid corner).
  std::vector<std::uint8_t> pattern(cells);
  tbb::parallel_for(std::size_t{0}, cells, [&](std::size_t i) {
    int p = 0;
    for (int c = 0; c < 8; ++c) {
      const std::uint32_t k = grid.cell_corners[i][static_cast<std::size_t>(c)];
      if (!field.valid[k]) {
        p = 0;
        break;
      }
      p |= (field.values[k] < config.iso ? 1 : 0) << c;
    }
    pattern[i] = static_cast<std::uint8_t>(p == 255 ? 0 : p);
  });
  const std::vector<std::uint32_t> active =
      parallel_select_indices(cells, [&](std::size_t i) { return pattern[i] != 0; });

  // 2. Crossed edges of active cells, one vertex each. Every cell sharing an edge marks it in a
  // table over all grid edges with the same value (its upper corner; relaxed atomics, no
  // order needed), then vertices are numbered in table order by a parallel scan over fixed
  // blocks, so numbering and positions do not depend on the thread count.
  const std::size_t table_size = grid.corners.size() * 3;
  std::unique_ptr<std::atomic<std::uint32_t>[]> upper(new std::atomic<std::uint32_t>[table_size]);
  tbb::parallel_for(std::size_t{0}, table_size,
                    [&](std::size_t k) { upper[k].store(kNoEdge, std::memory_order_relaxed); });
  tbb::parallel_for(std::size_t{0}, active.size(), [&](std::size_t a) {
    const auto& corners = grid.cell_corners[active[a]];
    for_each_crossed_edge(pattern[active[a]], [&](int e, int, int c1) {
      upper[edge_key(corners, e)].store(corners[static_cast<std::size_t>(c1)],
                                        std::memory_order_relaxed);
    });
  });
  const std::size_t blocks = (table_size + kParallelBlock - 1) / kParallelBlock;
  std::vector<std::uint32_t> block_offsets(blocks);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    std::uint32_t count = 0;
    for (std::size_t k = b * kParallelBlock; k < std::min(table_size, (b + 1) * kParallelBlock);
         ++k)
      count += upper[k].load(std::memory_order_relaxed) != kNoEdge ? 1u : 0u;
    block_offsets[b] = count;
  });
  TriangleMesh mesh;
  mesh.vertices.resize(exclusive_scan_in_place(block_offsets));
  std::vector<std::uint32_t> edge_vertex(table_size);  // valid where upper[k] != kNoEdge
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    std::uint32_t v = block_offsets[b];
    for (std::size_t k = b * kParallelBlock; k < std::min(table_size, (b + 1) * kParallelBlock);
         ++k) {
      const std::uint32_t hi = upper[k].load(std::memory_order_relaxed);
      if (hi == kNoEdge) continue;
      const auto lo = static_cast<std::uint32_t>(k / 3);
      const float d0 = field.values[lo] - config.iso, d1 = field.values[hi] - config.iso;
      const float t = std::clamp(d0 / (d0 - d1), 1e-3f, 1.0f - 1e-3f);
      mesh.vertices[v] = grid.corner_position(lo) * (1.0f - t) + grid.corner_position(hi) * t;
      edge_vertex[k] = v++;
    }
  });

  // 3. Triangles per active cell, in cell order.
  std::vector<std::uint32_t> tri_offsets(active.size());
  tbb::parallel_for(std::size_t{0}, active.size(), [&](std::size_t a) {
    tri_offsets[a] = static_cast<std::uint32_t>(cases[pattern[active[a]]].triangles.size());
  });
  mesh.triangles.resize(exclusive_scan_in_place(tri_offsets));
  tbb::parallel_for(std::size_t{0}, active.size(), [&](std::size_t a) {
    const std::size_t cell = active[a];
    const int p = pattern[cell];
    auto vertex_of = [&](int e) { return edge_vertex[edge_key(grid.cell_corners[cell], e)]; };
    std::uint32_t at = tri_offsets[a];
    for (const auto& tri : cases[p].triangles) {
      mesh.triangles[at++] = Triangle{vertex_of(tri[0]), vertex_of(tri[1]), vertex_of(tri[2])};
    }
  });
  if (config.vertex_normals) compute_vertex_normals(mesh);
  return mesh;
}

}  // namespace meshflow
