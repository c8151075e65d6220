#include "nodes/triangulate/quad_triangles.h"

#include <array>

namespace meshflow {

void append_quad_triangles(const PointGrid& g, int u, int v, std::vector<Triangle>& out) {
  // Corners 0 = (u, v), 1 = (u + 1, v), 2 = (u, v + 1), 3 = (u + 1, v + 1).
  const std::size_t i0 = g.index(u, v), i2 = g.index(u, v + 1);
  const std::array<std::size_t, 4> id = {i0, i0 + 1, i2, i2 + 1};
  int valid = 0;
  for (int c = 0; c < 4; ++c) valid |= (g.valid(id[static_cast<std::size_t>(c)]) ? 1 : 0) << c;
  std::array<std::array<int, 3>, 2> tris{};
  int n = 0;
  switch (valid) {
    case 15:  // along the shorter diagonal
      if ((g.points[id[0]] - g.points[id[3]]).squaredNorm() <=
          (g.points[id[1]] - g.points[id[2]]).squaredNorm())
        tris = {{{0, 2, 3}, {0, 3, 1}}};
      else
        tris = {{{0, 2, 1}, {1, 2, 3}}};
      n = 2;
      break;
    case 7:  // corner 3 missing
      tris[0] = {0, 2, 1};
      n = 1;
      break;
    case 14:  // corner 0 missing
      tris[0] = {1, 2, 3};
      n = 1;
      break;
    case 13:  // corner 1 missing
      tris[0] = {0, 2, 3};
      n = 1;
      break;
    case 11:  // corner 2 missing
      tris[0] = {0, 3, 1};
      n = 1;
      break;
    default:
      break;
  }
  for (int k = 0; k < n; ++k) {
    const auto& t = tris[static_cast<std::size_t>(k)];
    const std::size_t a = id[static_cast<std::size_t>(t[0])],
                      b = id[static_cast<std::size_t>(t[1])],
                      c = id[static_cast<std::size_t>(t[2])];
    out.push_back(Triangle{static_cast<std::uint32_t>(a), static_cast<std::uint32_t>(b),
                           static_cast<std::uint32_t>(c)});
  }
}

}  // namespace meshflow
