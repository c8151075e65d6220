#include "nodes/extract/marching_cubes.h"

#include <tbb/parallel_for.h>

#include <algorithm>

#include "nodes/extract/cell_patterns.h"
#include "nodes/extract/cube_table.h"
#include "nodes/extract/edge_vertices.h"
#include "runtime/parallel.h"

namespace meshflow {
namespace {

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
  const CellPatterns cells = cell_patterns(grid, field, config.iso);
  const auto& active = cells.active;

  // Crossed edges of active cells, one vertex each (numbered in edge-table order, so numbering
  // and positions do not depend on the thread count).
  EdgeVertexTable edges(grid.corners.size(), 3);
  auto segment_of = [&](const std::array<std::uint32_t, 8>& corners, int e) {
    const auto& ce = kCubeEdges[static_cast<std::size_t>(e)];
    return edges.segment(corners[static_cast<std::size_t>(ce[0])],
                         static_cast<std::size_t>(kCubeEdgeAxis[static_cast<std::size_t>(e)]));
  };
  tbb::parallel_for(std::size_t{0}, active.size(), [&](std::size_t a) {
    const auto& corners = grid.cell_corners[active[a]];
    for_each_crossed_edge(cells.pattern[active[a]], [&](int e, int, int c1) {
      edges.mark(segment_of(corners, e), corners[static_cast<std::size_t>(c1)]);
    });
  });
  TriangleMesh mesh;
  mesh.vertices = edges.place_vertices(grid, field, config.iso);

  // Triangles per active cell, in cell order.
  std::vector<std::uint32_t> tri_offsets(active.size());
  tbb::parallel_for(std::size_t{0}, active.size(), [&](std::size_t a) {
    tri_offsets[a] = static_cast<std::uint32_t>(cases[cells.pattern[active[a]]].triangles.size());
  });
  mesh.triangles.resize(exclusive_scan_in_place(tri_offsets));
  tbb::parallel_for(std::size_t{0}, active.size(), [&](std::size_t a) {
    const std::size_t cell = active[a];
    auto vertex_of = [&](int e) { return edges.vertex(segment_of(grid.cell_corners[cell], e)); };
    std::uint32_t at = tri_offsets[a];
    for (const auto& tri : cases[cells.pattern[cell]].triangles) {
      mesh.triangles[at++] = Triangle{vertex_of(tri[0]), vertex_of(tri[1]), vertex_of(tri[2])};
    }
  });
  if (config.vertex_normals) compute_vertex_normals(mesh);
  return mesh;
}

}  // namespace meshflow
