#include "nodes/voxelize/voxelize.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>

#include "runtime/error.h"

namespace meshflow {
namespace {

TEST(SparseGrid, MatchesBruteForceCellAndCornerSets) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-0.5f, 0.5f);
  PointCloud c;
  for (int i = 0; i < 500; ++i) c.positions.emplace_back(u(rng), u(rng), 0.3f * u(rng));
  const float voxel = 0.07f;
  for (float margin : {0.0f, 0.5f, 1.3f}) {
    const SparseGrid grid = voxelize(c, VoxelizeConfig{voxel, margin});
    std::set<VoxelKey> cells, corners;
    for (const auto& p : c.positions) {
      // Brute force: test every cell within 3 of the point's cell for overlap with its cube.
      const Eigen::Vector3i cell = cell_of(p, voxel);
      for (int dz = -3; dz <= 3; ++dz)
        for (int dy = -3; dy <= 3; ++dy)
          for (int dx = -3; dx <= 3; ++dx) {
            const Eigen::Vector3i q = cell + Eigen::Vector3i(dx, dy, dz);
            const Eigen::Vector3f lo = q.cast<float>() * voxel;
            const Eigen::Vector3f hi = lo + Eigen::Vector3f::Constant(voxel);
            const Eigen::Vector3f r = Eigen::Vector3f::Constant(margin * voxel);
            if (((p + r).array() >= lo.array()).all() && ((p - r).array() < hi.array()).all()) {
              cells.insert(pack_key(q));
            }
          }
    }
    for (VoxelKey k : cells)
      for (int i = 0; i < 8; ++i)
        corners.insert(pack_key(unpack_key(k) + Eigen::Vector3i(i & 1, (i >> 1) & 1, i >> 2)));
    if (margin == 0.0f || margin >= 1.0f) {
      EXPECT_EQ(grid.cells, std::vector<VoxelKey>(cells.begin(), cells.end()))
          << "margin " << margin;
      EXPECT_EQ(grid.corners, std::vector<VoxelKey>(corners.begin(), corners.end()));
    } else {
      // Block-flag expansion: every exact cell, plus only neighbours of occupied cells.
      std::set<VoxelKey> occupied;
      for (const auto& p : c.positions) occupied.insert(pack_key(cell_of(p, voxel)));
      const std::set<VoxelKey> got(grid.cells.begin(), grid.cells.end());
      EXPECT_TRUE(std::includes(got.begin(), got.end(), cells.begin(), cells.end()));
      EXPECT_LT(got.size(), cells.size() * 11 / 10) << "few extra cells";
      for (VoxelKey k : got) {
        bool near = false;
        for (int i = 0; i < 27 && !near; ++i) {
          near = occupied.count(pack_key(unpack_key(k) +
                                         Eigen::Vector3i(i % 3 - 1, i / 3 % 3 - 1, i / 9 - 1))) > 0;
        }
        EXPECT_TRUE(near);
      }
    }
    for (std::size_t i = 0; i < grid.cells.size(); ++i) {
      const Eigen::Vector3f origin = unpack_key(grid.cells[i]).cast<float>() * voxel;
      for (int k = 0; k < 8; ++k) {
        const Eigen::Vector3f expected =
            origin + voxel * Eigen::Vector3f(k & 1, (k >> 1) & 1, k >> 2);
        EXPECT_TRUE(grid.corner_position(grid.cell_corners[i][static_cast<std::size_t>(k)])
                        .isApprox(expected, 1e-5f));
      }
    }
  }
}

TEST(SparseGrid, RejectsCoordinatesBeyondTheKeyRange) {
  PointCloud c;
  c.positions = {{0, 0, 0}, {1e5f, 0, 0}};
  EXPECT_THROW(voxelize(c, VoxelizeConfig{0.01f, 0.5f}), Error);
  EXPECT_THROW(voxelize(c, VoxelizeConfig{0.0f, 0.5f}), Error);
  c.positions.pop_back();
  EXPECT_THROW(voxelize(c, VoxelizeConfig{0.01f, -1.0f}), Error);
}

TEST(SparseGrid, FloorToIntMatchesStdFloor) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-3e5f, 3e5f);
  for (int i = 0; i < 100000; ++i) {
    const float x = i < 50 ? static_cast<float>(i - 25) * 0.5f : u(rng);
    EXPECT_EQ(floor_to_int(x), static_cast<std::int32_t>(std::floor(x))) << x;
  }
  EXPECT_EQ(floor_to_int(-0.0f), 0);
  EXPECT_EQ(floor_to_int(-1e-30f), -1);
  EXPECT_EQ(floor_to_int(1e20f), 1 << 30);
  EXPECT_EQ(floor_to_int(-std::numeric_limits<float>::infinity()), -(1 << 30));
  EXPECT_EQ(floor_to_int(std::numeric_limits<float>::quiet_NaN()), -(1 << 30));
  EXPECT_FALSE(cell_index_in_range(cell_of({1e20f, 0, 0}, 0.01f)));
}

TEST(SparseGrid, KeysRoundTrip) {
  for (const Eigen::Vector3i& c : {Eigen::Vector3i(0, 0, 0), Eigen::Vector3i(-5, 7, -200000),
                                   Eigen::Vector3i(kMaxCellIndex, -kMaxCellIndex, 3)}) {
    EXPECT_EQ(unpack_key(pack_key(c)), c);
  }
  EXPECT_LT(pack_key({5, 0, 0}), pack_key({0, 1, 0}));
  EXPECT_LT(pack_key({0, 9, 0}), pack_key({0, 0, 1}));
}

}  // namespace
}  // namespace meshflow
