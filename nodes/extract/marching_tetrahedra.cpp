#include "nodes/extract/marching_tetrahedra.h"

#include <tbb/parallel_for.h>

#include <array>
#include <vector>

#include "nodes/extract/cell_patterns.h"
#include "nodes/extract/edge_vertices.h"
#include "runtime/parallel.h"

namespace meshflow {
namespace {

// Lattice segments of a cell: corner pairs (lo, hi) with lo's bits a proper subset of hi's
// (cube corner c is at (c & 1, c >> 1 & 1, c >> 2 & 1)). 19 of them; the direction of a segment
// is hi ^ lo (1..7), so it is shared with every cell containing it.
struct CellSegment {
  int lo, hi;
};

struct TetraTable {
  std::vector<CellSegment> segments;                           // 19
  std::array<std::vector<std::array<int, 3>>, 256> triangles;  // per pattern, segment ids
};

bool is_subset(int a, int b) { return (a & ~b) == 0; }

Eigen::Vector3f unit_corner(int c) {
  return {static_cast<float>(c & 1), static_cast<float>((c >> 1) & 1),
          static_cast<float>((c >> 2) & 1)};
}

TetraTable build_table() {
  TetraTable t;
  std::array<std::array<int, 8>, 8> id{};
  for (int hi = 0; hi < 8; ++hi)
    for (int lo = 0; lo < 8; ++lo)
      if (lo != hi && is_subset(lo, hi)) {
        id[static_cast<std::size_t>(lo)][static_cast<std::size_t>(hi)] =
            static_cast<int>(t.segments.size());
        t.segments.push_back({lo, hi});
      }
  auto segment = [&](int a, int b) {
    return a < b ? id[static_cast<std::size_t>(a)][static_cast<std::size_t>(b)]
                 : id[static_cast<std::size_t>(b)][static_cast<std::size_t>(a)];
  };
  auto midpoint = [&](int a, int b) -> Eigen::Vector3f {
    return 0.5f * (unit_corner(a) + unit_corner(b));
  };
  const int axes[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int pattern = 0; pattern < 256; ++pattern) {
    auto& out = t.triangles[static_cast<std::size_t>(pattern)];
    for (const auto& ax : axes) {
      const int a = 1 << ax[0], ab = a | (1 << ax[1]);
      const std::array<int, 4> tet = {0, a, ab, 7};
      std::vector<int> in, outside;
      for (int c : tet) ((pattern >> c) & 1 ? in : outside).push_back(c);
      if (in.empty() || outside.empty()) continue;
      Eigen::Vector3f ref = Eigen::Vector3f::Zero();  // inside -> outside
      for (int c : outside) ref += unit_corner(c) / static_cast<float>(outside.size());
      for (int c : in) ref -= unit_corner(c) / static_cast<float>(in.size());
      auto emit = [&](std::array<std::array<int, 2>, 3> e) {
        const Eigen::Vector3f p0 = midpoint(e[0][0], e[0][1]), p1 = midpoint(e[1][0], e[1][1]),
                              p2 = midpoint(e[2][0], e[2][1]);
        if ((p1 - p0).cross(p2 - p0).dot(ref) < 0.0f) std::swap(e[1], e[2]);
        out.push_back(
            {segment(e[0][0], e[0][1]), segment(e[1][0], e[1][1]), segment(e[2][0], e[2][1])});
      };
      if (in.size() == 2) {  // a quad: (i0 o0, i0 o1, i1 o1, i1 o0) as two triangles
        const int i0 = in[0], i1 = in[1], o0 = outside[0], o1 = outside[1];
        emit({{{i0, o0}, {i0, o1}, {i1, o1}}});
        emit({{{i0, o0}, {i1, o1}, {i1, o0}}});
      } else {  // one corner alone on its side: a triangle around it
        const std::vector<int>& lone = in.size() == 1 ? in : outside;
        const std::vector<int>& rest = in.size() == 1 ? outside : in;
        emit({{{lone[0], rest[0]}, {lone[0], rest[1]}, {lone[0], rest[2]}}});
      }
    }
  }
  return t;
}

const TetraTable& tetra_table() {
  static const TetraTable table = build_table();
  return table;
}

}  // namespace

TriangleMesh marching_tetrahedra(const SparseGrid& grid, const DistanceField& field,
                                 const ExtractConfig& config) {
  const TetraTable& table = tetra_table();
  const CellPatterns cells = cell_patterns(grid, field, config.iso);
  const auto& active = cells.active;

  EdgeVertexTable edges(grid.corners.size(), 7);
  auto segment_of = [&](std::size_t cell, int s) {
    const CellSegment& cs = table.segments[static_cast<std::size_t>(s)];
    return edges.segment(grid.cell_corners[cell][static_cast<std::size_t>(cs.lo)],
                         static_cast<std::size_t>((cs.hi ^ cs.lo) - 1));
  };
  tbb::parallel_for(std::size_t{0}, active.size(), [&](std::size_t a) {
    const std::size_t cell = active[a];
    const int p = cells.pattern[cell];
    for (std::size_t s = 0; s < table.segments.size(); ++s) {
      const CellSegment& cs = table.segments[s];
      if (((p >> cs.lo) & 1) != ((p >> cs.hi) & 1))
        edges.mark(segment_of(cell, static_cast<int>(s)),
                   grid.cell_corners[cell][static_cast<std::size_t>(cs.hi)]);
    }
  });
  TriangleMesh mesh;
  mesh.vertices = edges.place_vertices(grid, field, config.iso);

  std::vector<std::uint32_t> offsets(active.size());
  tbb::parallel_for(std::size_t{0}, active.size(), [&](std::size_t a) {
    offsets[a] = static_cast<std::uint32_t>(table.triangles[cells.pattern[active[a]]].size());
  });
  mesh.triangles.resize(exclusive_scan_in_place(offsets));
  tbb::parallel_for(std::size_t{0}, active.size(), [&](std::size_t a) {
    const std::size_t cell = active[a];
    std::uint32_t at = offsets[a];
    for (const auto& tri : table.triangles[cells.pattern[cell]]) {
      mesh.triangles[at++] =
          Triangle{edges.vertex(segment_of(cell, tri[0])), edges.vertex(segment_of(cell, tri[1])),
                   edges.vertex(segment_of(cell, tri[2]))};
    }
  });
  if (config.vertex_normals) compute_vertex_normals(mesh);
  return mesh;
}

}  // namespace meshflow
