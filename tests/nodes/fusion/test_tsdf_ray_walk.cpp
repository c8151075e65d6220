// The along-ray integrator's voxel walk (tsdf_ray_walk.h) against an exact oracle: the cells a
// segment crosses, found by clipping it to each candidate cell in double precision. Since the
// integrator walks each ray once and keeps those voxels, the walk alone decides which voxels a
// ray updates.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "nodes/fusion/tsdf_ray_walk.h"

namespace meshflow {
namespace {

using WalkCell = std::tuple<int, int, int>;

// The segment a -> b's parameter range inside the cube of `cell` (the unit cube centred on it)
// shrunk by `inset` on every side, in double precision; empty when t0 >= t1.
std::pair<double, double> segment_in_cell(const double a[3], const double b[3],
                                          const WalkCell& cell, double inset) {
  const int c[3] = {std::get<0>(cell), std::get<1>(cell), std::get<2>(cell)};
  double t0 = 0.0, t1 = 1.0;
  for (int i = 0; i < 3; ++i) {
    const double lo = c[i] - 0.5 + inset, hi = c[i] + 0.5 - inset, d = b[i] - a[i];
    if (d == 0.0) {
      if (a[i] < lo || a[i] > hi) return {1.0, 0.0};
      continue;
    }
    const double e = (lo - a[i]) / d, l = (hi - a[i]) / d;
    t0 = std::max(t0, std::min(e, l));
    t1 = std::min(t1, std::max(e, l));
  }
  return {t0, t1};
}

TEST(TsdfRayWalk, VisitsExactlyTheCellsTheSegmentCrosses) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> where(-40.0f, 40.0f), direction(-1.0f, 1.0f),
      length(0.0f, 14.0f);
  std::size_t visited_total = 0;
  for (int n = 0; n < 20000; ++n) {
    const ray_walk::Floats4 from{where(rng), where(rng), where(rng), 0.0f};
    ray_walk::Floats4 dir{direction(rng), direction(rng), direction(rng), 0.0f};
    if (n % 10 == 0) dir[n % 3] = 0.0f;        // segments in a plane of the grid
    if (n % 50 == 0) dir[(n + 1) % 3] = 0.0f;  // along an axis
    const ray_walk::Floats4 to = from + dir * length(rng);
    std::vector<WalkCell> cells;
    walk_voxels(from, to, [&](const ray_walk::Ints4& c) {
      ASSERT_EQ(c[3], 0);
      cells.emplace_back(c[0], c[1], c[2]);
    });
    ASSERT_FALSE(cells.empty());
    visited_total += cells.size();
    const double a[3] = {from[0], from[1], from[2]}, b[3] = {to[0], to[1], to[2]};
    // Starts in the first point's cell, steps to a face neighbour each time, each axis one way,
    // and every cell it visits the segment crosses (up to float rounding at edges and corners).
    EXPECT_EQ(cells.front(), WalkCell(static_cast<int>(std::floor(a[0] + 0.5)),
                                      static_cast<int>(std::floor(a[1] + 0.5)),
                                      static_cast<int>(std::floor(a[2] + 0.5))));
    int last_step[3] = {0, 0, 0};
    for (std::size_t i = 0; i < cells.size(); ++i) {
      const auto [t0, t1] = segment_in_cell(a, b, cells[i], -1e-4);
      EXPECT_LE(t0, t1) << "visited a cell the segment misses, segment " << n << " cell " << i;
      if (i == 0) continue;
      const int d[3] = {std::get<0>(cells[i]) - std::get<0>(cells[i - 1]),
                        std::get<1>(cells[i]) - std::get<1>(cells[i - 1]),
                        std::get<2>(cells[i]) - std::get<2>(cells[i - 1])};
      ASSERT_EQ(std::abs(d[0]) + std::abs(d[1]) + std::abs(d[2]), 1) << "segment " << n;
      for (int k = 0; k < 3; ++k) {
        if (d[k] == 0) continue;
        EXPECT_NE(d[k], -last_step[k]) << "axis " << k << " turned back, segment " << n;
        last_step[k] = d[k];
      }
    }
    // Every cell the segment crosses more than a rounding's depth inside is visited.
    const std::set<WalkCell> seen(cells.begin(), cells.end());
    EXPECT_EQ(seen.size(), cells.size()) << "a cell visited twice, segment " << n;
    int lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
      lo[k] = static_cast<int>(std::floor(std::min(a[k], b[k]) + 0.5)) - 1;
      hi[k] = static_cast<int>(std::floor(std::max(a[k], b[k]) + 0.5)) + 1;
    }
    for (int x = lo[0]; x <= hi[0]; ++x)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int z = lo[2]; z <= hi[2]; ++z) {
          const auto [t0, t1] = segment_in_cell(a, b, WalkCell(x, y, z), 1e-3);
          if (t0 < t1) {
            EXPECT_TRUE(seen.count(WalkCell(x, y, z)))
                << "missed cell (" << x << ", " << y << ", " << z << "), segment " << n;
          }
        }
  }
  EXPECT_GT(visited_total, 200000u);
}

}  // namespace
}  // namespace meshflow
