#include "nodes/triangulate/depth_triangulation.h"

#include <tbb/parallel_for.h>

#include <utility>

#include "nodes/triangulate/quad_triangles.h"
#include "runtime/parallel.h"

namespace meshflow {
namespace {

// Two triangles per valid quad, rows in parallel, joined in row order.
std::vector<Triangle> naive_triangles(const PointGrid& g, const OcclusionTriangleTest& keep,
                                      TriangulationCounts* counts) {
  const std::size_t rows = static_cast<std::size_t>(g.height - 1);
  std::vector<std::vector<Triangle>> per_row(rows);
  std::vector<OcclusionRejections> rejected(rows);
  tbb::parallel_for(std::size_t{0}, rows, [&](std::size_t v) {
    per_row[v].reserve(2 * static_cast<std::size_t>(g.width));
    for (int u = 0; u + 1 < g.width; ++u)
      append_quad_triangles(g, u, static_cast<int>(v), per_row[v]);
    keep.filter(g, per_row[v], 0, &rejected[v]);
  });
  std::vector<Triangle> out = concatenate_parts(per_row);
  if (counts != nullptr)
    for (const OcclusionRejections& r : rejected) {
      counts->rejected_view += r.view;
      counts->rejected_shape += r.shape;
    }
  return out;
}

}  // namespace

std::vector<Triangle> triangulate_grid(const PointGrid& grid,
                                       const DepthTriangulationConfig& config,
                                       TriangulationCounts* counts) {
  if (grid.width < 2 || grid.height < 2) return {};
  const OcclusionTriangleTest keep(config.max_view_angle_deg, config.max_edge_ratio);
  if (config.method == DepthTriangulationMethod::kRestrictedQuadtree)
    return restricted_quadtree_triangles(
        grid, keep, config.quadtree, counts != nullptr ? &counts->threshold_per_depth2 : nullptr);
  return naive_triangles(grid, keep, counts);
}

namespace {

// Triangulates and compacts `grid` (made with c.filter filled in); reports c through `counts`.
TriangleMesh grid_mesh(const PointGrid& grid, const DepthTriangulationConfig& config,
                       TriangulationCounts& c, TriangulationCounts* counts) {
  std::vector<Triangle> triangles = triangulate_grid(grid, config, &c);
  // Vertices numbered first, so that the repairs below work over the used pixels (a tenth of
  // the grid for a quadtree) rather than over every pixel.
  std::vector<std::uint32_t> pixels = renumber_used_vertices(triangles, grid.points.size());
  const std::size_t triangulated = triangles.size();
  if (config.repair_non_manifold_vertices) remove_smaller_fans(triangles, pixels.size(), &c.fans);
  remove_small_components(triangles, pixels.size(), config.min_component_triangles, &c.components);
  if (triangles.size() != triangulated) {  // the removed triangles' own vertices are unused now
    std::vector<std::uint32_t> kept = renumber_used_vertices(triangles, pixels.size());
    for (std::uint32_t& vertex : kept) vertex = pixels[vertex];
    pixels = std::move(kept);
  }
  TriangleMesh mesh = mesh_from_grid_pixels(grid, pixels, std::move(triangles));
  if (config.decimate_to > 0.0f && config.decimate_to < 1.0f) {
    QemConfig qem = config.decimation;
    qem.target_ratio = config.decimate_to;
    qem.viewpoint = grid.eye;
    mesh = qem_decimate(mesh, qem);
  }
  if (counts != nullptr) *counts = c;
  return mesh;
}

}  // namespace

TriangleMesh triangulate_depth(const DepthFrame& frame, const DepthTriangulationConfig& config,
                               TriangulationCounts* counts) {
  TriangulationCounts c;
  return grid_mesh(grid_from_depth(frame, config.filter, &c.filter), config, c, counts);
}

TriangleMesh triangulate_organized(const PointCloud& cloud, const DepthTriangulationConfig& config,
                                   TriangulationCounts* counts) {
  TriangulationCounts c;
  return grid_mesh(grid_from_organized(cloud, config.filter, &c.filter), config, c, counts);
}

}  // namespace meshflow
