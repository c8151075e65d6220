#include "nodes/search/spatial_index.h"

#include <gtest/gtest.h>

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
