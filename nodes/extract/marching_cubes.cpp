#include "nodes/extract/marching_cubes.h"

#include <tbb/parallel_for.h>

#include <algorithm>

#include "nodes/extract/cube_edges.h"
#include "runtime/parallel.h"

namespace meshflow {

TriangleMesh marching_cubes(const SparseGrid& grid, const DistanceField& field,
                            const ExtractConfig& config) {
  const auto& cases = cube_cases();
  const CellPatterns cells = cell_patterns(grid, field, config.iso);
  const auto& active = cells.active;

  // Crossed edges of active cells, one vertex each (numbered in edge-table order, so numbering
  // and positions do not depend on the thread count).
  EdgeVertexTable edges = mark_crossed_cube_edges(grid, cells);
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
    auto vertex_of = [&](int e) {
      return edges.vertex(cube_edge_segment(edges, grid.cell_corners[cell], e));
    };
    std::uint32_t at = tri_offsets[a];
    for (const auto& tri : cases[cells.pattern[cell]].triangles) {
      mesh.triangles[at++] = Triangle{vertex_of(tri[0]), vertex_of(tri[1]), vertex_of(tri[2])};
    }
  });
  if (config.vertex_normals) compute_vertex_normals(mesh);
  return mesh;
}

}  // namespace meshflow
