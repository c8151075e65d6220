#include "nodes/extract/marching_cubes.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>

#include "nodes/extract/cube_table.h"
#include "runtime/parallel.h"

namespace meshflow {
namespace {

// A crossed grid edge as one active cell sees it: key = lower corner index * 3 + axis,
// `upper` = its other corner, `slot` = where the cell listed it (cells list their crossed edges
// in local edge order, so a cell finds the vertex of its k-th crossed edge at its k-th slot).
struct EdgeRef {
  std::uint64_t key;
  std::uint32_t upper;
  std::uint32_t slot;
  bool operator<(const EdgeRef& o) const { return key < o.key || (key == o.key && slot < o.slot); }
};

std::uint64_t edge_key(const std::array<std::uint32_t, 8>& corners, int e) {
  return static_cast<std::uint64_t>(
             corners[static_cast<std::size_t>(kCubeEdges[static_cast<std::size_t>(e)][0])]) *
             3 +
         static_cast<std::uint64_t>(kCubeEdgeAxis[static_cast<std::size_t>(e)]);
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

  // 2. Crossed edges of active cells, sorted and unique: one vertex each.
  std::vector<std::uint32_t> edge_offsets(active.size());
  tbb::parallel_for(std::size_t{0}, active.size(), [&](std::size_t a) {
    const int p = pattern[active[a]];
    std::uint32_t count = 0;
    for (const auto& e : kCubeEdges) count += ((p >> e[0]) & 1) != ((p >> e[1]) & 1) ? 1u : 0u;
    edge_offsets[a] = count;
  });
  std::vector<EdgeRef> edges(exclusive_scan_in_place(edge_offsets));
  tbb::parallel_for(std::size_t{0}, active.size(), [&](std::size_t a) {
    const std::size_t cell = active[a];
    const int p = pattern[cell];
    std::uint32_t at = edge_offsets[a];
    for (int e = 0; e < 12; ++e) {
      const auto& ce = kCubeEdges[static_cast<std::size_t>(e)];
      if (((p >> ce[0]) & 1) == ((p >> ce[1]) & 1)) continue;
      edges[at] = EdgeRef{edge_key(grid.cell_corners[cell], e),
                          grid.cell_corners[cell][static_cast<std::size_t>(ce[1])], at};
      ++at;
    }
  });
  tbb::parallel_sort(edges.begin(), edges.end());
  // One vertex per distinct key, numbered in key order; every slot learns its vertex.
  std::vector<std::uint32_t> slot_vertex(edges.size());
  std::size_t unique = 0;
  for (std::size_t i = 0; i < edges.size(); ++i) {
    if (unique == 0 || edges[i].key != edges[unique - 1].key) edges[unique++] = edges[i];
    slot_vertex[edges[i].slot] = static_cast<std::uint32_t>(unique - 1);
  }
  edges.resize(unique);

  TriangleMesh mesh;
  mesh.vertices.resize(edges.size());
  tbb::parallel_for(std::size_t{0}, edges.size(), [&](std::size_t v) {
    const auto lower = static_cast<std::uint32_t>(edges[v].key / 3);
    const std::uint32_t upper = edges[v].upper;
    const float d0 = field.values[lower] - config.iso, d1 = field.values[upper] - config.iso;
    const float t = std::clamp(d0 / (d0 - d1), 1e-3f, 1.0f - 1e-3f);
    mesh.vertices[v] = grid.corner_position(lower) * (1.0f - t) + grid.corner_position(upper) * t;
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
    std::array<std::uint32_t, 12> local_vertex{};  // vertex of each crossed local edge
    std::uint32_t slot = edge_offsets[a];
    for (int e = 0; e < 12; ++e) {
      const auto& ce = kCubeEdges[static_cast<std::size_t>(e)];
      if (((p >> ce[0]) & 1) != ((p >> ce[1]) & 1))
        local_vertex[static_cast<std::size_t>(e)] = slot_vertex[slot++];
    }
    auto vertex_of = [&](int e) { return local_vertex[static_cast<std::size_t>(e)]; };
    std::uint32_t at = tri_offsets[a];
    for (const auto& tri : cases[p].triangles) {
      mesh.triangles[at++] = Triangle{vertex_of(tri[0]), vertex_of(tri[1]), vertex_of(tri[2])};
    }
  });
  if (config.vertex_normals) compute_vertex_normals(mesh);
  return mesh;
}

}  // namespace meshflow
