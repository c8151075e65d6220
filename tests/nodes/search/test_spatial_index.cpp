#include "nodes/search/spatial_index.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace meshflow {
namespace {

TEST(SpatialIndex, KdTreeMatchesBruteForce) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-5.0f, 5.0f);
  std::vector<Eigen::Vector3f> pts(3000);
  for (auto& p : pts) p = {u(rng), u(rng), u(rng)};
  const KdTreeIndex tree(pts);
  const BruteForceIndex brute(pts);
  std::uint32_t ia[12], ib[12];
  float da[12], db[12];
  for (int q = 0; q < 200; ++q) {
    const Eigen::Vector3f query(u(rng), u(rng), u(rng));
    ASSERT_EQ(tree.knn(query, 12, ia, da), 12u);
    ASSERT_EQ(brute.knn(query, 12, ib, db), 12u);
    for (int k = 0; k < 12; ++k) {
      EXPECT_FLOAT_EQ(da[k], db[k]);
      EXPECT_FLOAT_EQ((pts[ia[k]] - query).squaredNorm(), da[k]);
    }
    EXPECT_EQ(tree.radius_search(query, 0.8f), brute.radius_search(query, 0.8f));
  }
}

// Points on an integer lattice, queried at lattice points and cell centres: many neighbours tie
// in distance. The kd-tree must return exactly the brute-force answer (ties by smaller index),
// whatever order its traversal meets them in.
TEST(SpatialIndex, TiesBreakBySmallerIndexLikeBruteForce) {
  std::vector<Eigen::Vector3f> pts;
  for (int z = 0; z < 8; ++z)
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x) pts.emplace_back(float(x), float(y), float(z));
  std::mt19937 rng(3);
  std::shuffle(pts.begin(), pts.end(), rng);  // indices unrelated to positions
  const KdTreeIndex tree(pts);
  const BruteForceIndex brute(pts);
  std::uint32_t ia[20], ib[20];
  float da[20], db[20];
  for (int z = 0; z < 8; ++z)
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x)
        for (const float offset : {0.0f, 0.5f}) {
          const Eigen::Vector3f q(float(x) + offset, float(y) + offset, float(z) + offset);
          for (const std::size_t k : {std::size_t{1}, std::size_t{7}, std::size_t{20}}) {
            ASSERT_EQ(brute.knn(q, k, ib, db), k);
            ASSERT_EQ(tree.knn(q, k, ia, da), k);
            for (std::size_t j = 0; j < k; ++j) {
              EXPECT_EQ(ia[j], ib[j]) << "k " << k << " rank " << j;
              EXPECT_EQ(da[j], db[j]);
            }
          }
        }
}

TEST(SpatialIndex, FewerPointsThanK) {
  const std::vector<Eigen::Vector3f> pts = {{0, 0, 0}, {1, 0, 0}};
  const KdTreeIndex tree(pts);
  std::uint32_t idx[5];
  float d2[5];
  EXPECT_EQ(tree.knn({0.9f, 0, 0}, 5, idx, d2), 2u);
  EXPECT_EQ(idx[0], 1u);
  const std::vector<Eigen::Vector3f> none;
  EXPECT_EQ(KdTreeIndex(none).knn({0, 0, 0}, 3, idx, d2), 0u);
}

}  // namespace
}  // namespace meshflow
