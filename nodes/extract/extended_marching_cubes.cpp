#include "nodes/extract/extended_marching_cubes.h"

#include <tbb/parallel_for.h>

#include <array>

#include "nodes/extract/cube_edges.h"
#include "nodes/extract/feature_edge_flips.h"
#include "runtime/error.h"
#include "runtime/parallel.h"

namespace meshflow {
namespace {

constexpr std::size_t kMaxLoops = 4;  // contour loops per cube case (at most 4)

// The feature vertex (if any) of each loop of one active cell.
struct CellFeatures {
  std::array<FeaturePoint, kMaxLoops> loop;
};

}  // namespace

TriangleMesh extended_marching_cubes(const SparseGrid& grid, const DistanceField& field,
                                     const PointCloud& cloud, const SpatialIndex& index,
                                     const ExtractConfig& config, const ExtendedMcConfig& emc) {
  if (cloud.normals.size() != cloud.positions.size())
    throw Error("extract", "method emc", "needs point normals");
  const auto& cases = cube_cases();
  const CellPatterns cells = cell_patterns(grid, field, config.iso);
  const auto& active = cells.active;
  EdgeVertexTable edges = mark_crossed_cube_edges(grid, cells);
  TriangleMesh mesh;
  mesh.vertices = edges.place_vertices(grid, field, config.iso);

  // Directed distances: each crossing moves onto the data along its grid edge.
  const std::size_t edge_vertices = mesh.vertices.size();
  std::vector<Eigen::Vector3f> hit_normals(edge_vertices);
  tbb::parallel_for(std::size_t{0}, edge_vertices, [&](std::size_t v) {
    const std::size_t s = edges.segment_of_vertex(static_cast<std::uint32_t>(v));
    const std::uint32_t lower = edges.lower(s);
    const EdgeHit hit =
        directed_edge_hit(grid.corner_position(lower), static_cast<int>(edges.direction(s)),
                          grid.voxel_size, field.values[lower] < config.iso, mesh.vertices[v],
                          config.iso, cloud, index, grid.voxel_size, emc.directed);
    mesh.vertices[v] = hit.position;
    hit_normals[v] = hit.normal;
  });

  // Feature detection per loop; counts of feature vertices and triangles per cell.
  std::vector<CellFeatures> features(active.size());
  std::vector<std::uint32_t> vertex_offsets(active.size()), tri_offsets(active.size());
  tbb::parallel_for(std::size_t{0}, active.size(), [&](std::size_t a) {
    const auto& corners = grid.cell_corners[active[a]];
    const Eigen::AlignedBox3f box(grid.corner_position(corners[0]),
                                  grid.corner_position(corners[7]));
    const CubeCase& cube = cases[cells.pattern[active[a]]];
    std::uint32_t feature_count = 0, tri_count = 0;
    for (std::size_t l = 0; l < cube.loops.size(); ++l) {
      const auto& loop = cube.loops[l];
      std::array<Eigen::Vector3f, 12> points, normals;
      for (std::size_t k = 0; k < loop.size(); ++k) {
        const std::uint32_t v = edges.vertex(cube_edge_segment(edges, corners, loop[k]));
        points[k] = mesh.vertices[v];
        normals[k] = hit_normals[v];
      }
      features[a].loop[l] =
          sharp_feature(points.data(), normals.data(), loop.size(), box, emc.feature);
      const bool fan = features[a].loop[l].kind != FeatureKind::kNone;
      feature_count += fan ? 1u : 0u;
      tri_count += static_cast<std::uint32_t>(fan ? loop.size() : loop.size() - 2);
    }
    vertex_offsets[a] = feature_count;
    tri_offsets[a] = tri_count;
  });
  const std::uint32_t feature_total = exclusive_scan_in_place(vertex_offsets);
  mesh.vertices.resize(edge_vertices + feature_total);
  mesh.triangles.resize(exclusive_scan_in_place(tri_offsets));

  // Fans around feature vertices, marching cubes' triangles elsewhere, in cell and loop order.
  tbb::parallel_for(std::size_t{0}, active.size(), [&](std::size_t a) {
    const auto& corners = grid.cell_corners[active[a]];
    auto vertex_of = [&](int e) { return edges.vertex(cube_edge_segment(edges, corners, e)); };
    const CubeCase& cube = cases[cells.pattern[active[a]]];
    std::uint32_t next_feature = static_cast<std::uint32_t>(edge_vertices) + vertex_offsets[a];
    std::uint32_t at = tri_offsets[a];
    std::size_t table_tri = 0;  // the loop's first triangle in cube.triangles
    for (std::size_t l = 0; l < cube.loops.size(); ++l) {
      const auto& loop = cube.loops[l];
      const std::size_t n = loop.size();
      const FeaturePoint& feature = features[a].loop[l];
      if (feature.kind != FeatureKind::kNone) {
        const std::uint32_t f = next_feature++;
        mesh.vertices[f] = feature.position;
        for (std::size_t k = 0; k < n; ++k)
          mesh.triangles[at++] = Triangle{f, vertex_of(loop[(k + 1) % n]), vertex_of(loop[k])};
      } else {
        for (std::size_t k = 0; k + 2 < n; ++k) {
          const auto& tri = cube.triangles[table_tri + k];
          mesh.triangles[at++] = Triangle{vertex_of(tri[0]), vertex_of(tri[1]), vertex_of(tri[2])};
        }
      }
      table_tri += n - 2;
    }
  });

  if (emc.flip_edges) {
    std::vector<std::uint8_t> is_feature(mesh.vertices.size(), 0);
    std::fill(is_feature.begin() + static_cast<std::ptrdiff_t>(edge_vertices), is_feature.end(),
              std::uint8_t{1});
    flip_edges_between_features(mesh, is_feature);
  }
  if (config.vertex_normals) compute_vertex_normals(mesh);
  return mesh;
}

}  // namespace meshflow
