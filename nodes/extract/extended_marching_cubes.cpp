#include "nodes/extract/extended_marching_cubes.h"

#include <tbb/parallel_for.h>

#include <array>

#include "nodes/extract/cube_edges.h"
#include "nodes/extract/feature_edge_flips.h"
#include "runtime/error.h"
#include "runtime/parallel.h"

namespace meshflow {
namespace {

// The active cells of a grid and their crossed edges, which every phase reads.
struct ActiveCells {
  const SparseGrid& grid;
  const CellPatterns& cells;
  const EdgeVertexTable& edges;

  // The vertex on local cube edge e of active cell a.
  std::uint32_t vertex(std::size_t a, int e) const {
    return edges.vertex(cube_edge_segment(edges, grid.cell_corners[cells.active[a]], e));
  }
};

// Moves every edge vertex onto the data along its grid edge (directed distance); returns the
// data's normal at each.
std::vector<Eigen::Vector3f> move_onto_data(std::vector<Eigen::Vector3f>& vertices,
                                            const ActiveCells& at, const DistanceField& field,
                                            const PointCloud& cloud, const SpatialIndex& index,
                                            float iso, const DirectedDistanceConfig& directed) {
  const SparseGrid& grid = at.grid;
  std::vector<Eigen::Vector3f> normals(vertices.size());
  tbb::parallel_for(std::size_t{0}, vertices.size(), [&](std::size_t v) {
    const std::size_t s = at.edges.segment_of_vertex(static_cast<std::uint32_t>(v));
    const std::uint32_t lower = at.edges.lower(s);
    const EdgeHit hit = directed_edge_hit(
        grid.corner_position(lower), static_cast<int>(at.edges.direction(s)), grid.voxel_size,
        field.values[lower] < iso, vertices[v], iso, cloud, index, grid.voxel_size, directed);
    vertices[v] = hit.position;
    normals[v] = hit.normal;
  });
  return normals;
}

// Whether each contour loop of the active cells fans around a feature vertex, the loops in cell
// order (a cell's own from loop_offsets: a byte per loop, where a feature point per possible
// loop took 64 bytes per cell), and where each cell's loops, feature vertices and triangles
// start in the output (exclusive sums).
struct CellLayout {
  std::vector<std::uint8_t> fan;
  std::vector<std::uint32_t> loop_offsets, vertex_offsets, triangle_offsets;
  std::uint32_t feature_vertices = 0, triangles = 0;
};

// The feature point of every loop (sharp_feature()) from the edge vertices `vertices` and the
// data's `normals` at them; the feature vertices appended to `vertices` in cell and loop order.
CellLayout detect_features(const ActiveCells& at, std::vector<Eigen::Vector3f>& vertices,
                           const std::vector<Eigen::Vector3f>& normals,
                           const SharpFeatureConfig& feature) {
  const auto& cases = cube_cases();
  const std::size_t count = at.cells.active.size();
  CellLayout layout;
  layout.loop_offsets.resize(count);
  tbb::parallel_for(std::size_t{0}, count, [&](std::size_t a) {
    layout.loop_offsets[a] =
        static_cast<std::uint32_t>(cases[at.cells.pattern[at.cells.active[a]]].loops.size());
  });
  std::vector<FeaturePoint> features(exclusive_scan_in_place(layout.loop_offsets));
  layout.vertex_offsets.resize(count);
  layout.triangle_offsets.resize(count);
  tbb::parallel_for(std::size_t{0}, count, [&](std::size_t a) {
    const auto& corners = at.grid.cell_corners[at.cells.active[a]];
    const Eigen::AlignedBox3f box(at.grid.corner_position(corners[0]),
                                  at.grid.corner_position(corners[7]));
    const CubeCase& cube = cases[at.cells.pattern[at.cells.active[a]]];
    std::uint32_t feature_count = 0, tri_count = 0;
    for (std::size_t l = 0; l < cube.loops.size(); ++l) {
      const auto& loop = cube.loops[l];
      std::array<Eigen::Vector3f, 12> points, loop_normals;
      for (std::size_t k = 0; k < loop.size(); ++k) {
        const std::uint32_t v = at.vertex(a, loop[k]);
        points[k] = vertices[v];
        loop_normals[k] = normals[v];
      }
      FeaturePoint& f = features[layout.loop_offsets[a] + l];
      f = sharp_feature(points.data(), loop_normals.data(), loop.size(), box, feature);
      const bool fan = f.kind != FeatureKind::kNone;
      feature_count += fan ? 1u : 0u;
      tri_count += static_cast<std::uint32_t>(fan ? loop.size() : loop.size() - 2);
    }
    layout.vertex_offsets[a] = feature_count;
    layout.triangle_offsets[a] = tri_count;
  });
  layout.feature_vertices = exclusive_scan_in_place(layout.vertex_offsets);
  layout.triangles = exclusive_scan_in_place(layout.triangle_offsets);
  const std::size_t first_feature = vertices.size();
  vertices.resize(first_feature + layout.feature_vertices);
  layout.fan.resize(features.size());
  tbb::parallel_for(std::size_t{0}, count, [&](std::size_t a) {
    std::size_t next = first_feature + layout.vertex_offsets[a];
    const std::uint32_t end =
        a + 1 < count ? layout.loop_offsets[a + 1] : static_cast<std::uint32_t>(features.size());
    for (std::uint32_t l = layout.loop_offsets[a]; l < end; ++l) {
      const bool fan = features[l].kind != FeatureKind::kNone;
      layout.fan[l] = fan ? 1 : 0;
      if (fan) vertices[next++] = features[l].position;
    }
  });
  return layout;
}

// Fans around feature vertices, marching cubes' triangles elsewhere, in cell and loop order;
// feature vertices numbered from `first_feature` (placed by detect_features()).
void emit_triangles(const ActiveCells& at, const CellLayout& layout, std::uint32_t first_feature,
                    TriangleMesh& mesh) {
  const auto& cases = cube_cases();
  tbb::parallel_for(std::size_t{0}, at.cells.active.size(), [&](std::size_t a) {
    const CubeCase& cube = cases[at.cells.pattern[at.cells.active[a]]];
    std::uint32_t next_feature = first_feature + layout.vertex_offsets[a];
    std::uint32_t out = layout.triangle_offsets[a];
    std::size_t table_tri = 0;  // the loop's first triangle in cube.triangles
    for (std::size_t l = 0; l < cube.loops.size(); ++l) {
      const auto& loop = cube.loops[l];
      const std::size_t n = loop.size();
      if (layout.fan[layout.loop_offsets[a] + l]) {
        const std::uint32_t f = next_feature++;
        for (std::size_t k = 0; k < n; ++k)
          mesh.triangles[out++] =
              Triangle{f, at.vertex(a, loop[(k + 1) % n]), at.vertex(a, loop[k])};
      } else {
        for (std::size_t k = 0; k + 2 < n; ++k) {
          const auto& tri = cube.triangles[table_tri + k];
          mesh.triangles[out++] =
              Triangle{at.vertex(a, tri[0]), at.vertex(a, tri[1]), at.vertex(a, tri[2])};
        }
      }
      table_tri += n - 2;
    }
  });
}

}  // namespace

TriangleMesh extended_marching_cubes(const SparseGrid& grid, const DistanceField& field,
                                     const PointCloud& cloud, const SpatialIndex& index,
                                     const ExtractConfig& config, const ExtendedMcConfig& emc,
                                     std::vector<std::uint8_t>* feature_vertices) {
  if (cloud.normals.size() != cloud.positions.size())
    throw Error("extract", "method emc", "needs point normals");
  TriangleMesh mesh;
  std::uint32_t edge_vertices = 0;
  {  // the cells' tables, freed before the flips and the normals
    const CellPatterns cells = cell_patterns(grid, field, config.iso);
    EdgeVertexTable edges = mark_crossed_cube_edges(grid, cells);
    mesh.vertices = edges.place_vertices(grid, field, config.iso);
    const ActiveCells active{grid, cells, edges};
    edge_vertices = static_cast<std::uint32_t>(mesh.vertices.size());
    const CellLayout layout = [&] {  // the data's normals at the vertices are freed after it
      const std::vector<Eigen::Vector3f> normals =
          move_onto_data(mesh.vertices, active, field, cloud, index, config.iso, emc.directed);
      return detect_features(active, mesh.vertices, normals, emc.feature);
    }();
    edges.release_marks();  // the triangles need only the vertex numbers
    mesh.triangles.resize(layout.triangles);
    emit_triangles(active, layout, edge_vertices, mesh);
  }
  std::vector<std::uint8_t> is_feature(mesh.vertices.size(), 0);
  std::fill(is_feature.begin() + static_cast<std::ptrdiff_t>(edge_vertices), is_feature.end(),
            std::uint8_t{1});
  if (emc.flip_edges) flip_edges_between_features(mesh, is_feature);
  if (feature_vertices) *feature_vertices = std::move(is_feature);
  if (config.vertex_normals) compute_vertex_normals(mesh);
  return mesh;
}

}  // namespace meshflow
