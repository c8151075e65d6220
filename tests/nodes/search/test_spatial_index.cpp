#include "nodes/search/spatial_index.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <utility>
#include <vector>

#include "test_support.h"

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

// knn_rows() of `tree` over `pts` for `queries` on 1 and 2 threads, every `stride`-th row
// compared with brute force's knn() (rank by rank: the same ties).
void expect_brute_force_rows(const std::vector<Eigen::Vector3f>& pts, const KdTreeIndex& tree,
                             const std::vector<Eigen::Vector3f>& queries, std::size_t k,
                             std::size_t stride) {
  const BruteForceIndex brute(pts);
  std::vector<std::uint32_t> want(k);
  std::vector<float> d2(k);
  for (const int threads : {1, 2}) {
    std::vector<std::uint32_t> rows(queries.size() * k, 0), counts(queries.size());
    test::with_threads(threads, [&] {
      tree.knn_rows(queries, k, rows.data(), counts.data());
      return 0;
    });
    for (std::size_t q = 0; q < queries.size(); q += stride) {
      const std::size_t found = brute.knn(queries[q], k, want.data(), d2.data());
      ASSERT_EQ(counts[q], found) << "query " << q;
      for (std::size_t j = 0; j < found; ++j)
        ASSERT_EQ(rows[q * k + j], want[j])
            << "query " << q << " rank " << j << ", k " << k << ", " << threads << " threads";
    }
  }
}

// knn_rows() is exact: the rows are brute force's, ties included, for the indexed points
// themselves (searched leaf by leaf) and for other queries, on 1 and 2 threads, with a small and
// a deep tree. Lattice points tie everywhere, also on the planes that split the set; random
// points on a noisy plane have neighbours across them.
TEST(SpatialIndex, KnnRowsAreBruteForceRows) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-5.0f, 5.0f);
  for (const int side : {10, 27}) {  // 1 000 points: one tree; 19 683: two
    std::vector<Eigen::Vector3f> lattice;
    for (int z = 0; z < side; ++z)
      for (int y = 0; y < side; ++y)
        for (int x = 0; x < side; ++x) lattice.emplace_back(float(x), float(y), float(z));
    std::shuffle(lattice.begin(), lattice.end(), rng);
    std::vector<Eigen::Vector3f> scattered(lattice.size());
    for (auto& p : scattered) p = {u(rng), u(rng), u(rng) * 0.01f};
    for (const std::vector<Eigen::Vector3f>* pts : {&lattice, &scattered}) {
      const KdTreeIndex tree(*pts);
      std::vector<Eigen::Vector3f> others(300);
      for (auto& p : others) p = {u(rng) + 5.0f, u(rng) + 5.0f, u(rng)};
      const std::size_t stride = pts->size() / 400 + 1;
      for (const std::size_t k : {std::size_t{1}, std::size_t{10}, std::size_t{27}}) {
        SCOPED_TRACE(testing::Message() << pts->size() << " points, k " << k);
        expect_brute_force_rows(*pts, tree, *pts, k, stride);
        expect_brute_force_rows(*pts, tree, others, k, 1);
      }
    }
  }
}

// knn() and radius_search() over a deep tree against brute force, with queries either side of
// the plane that splits the set first and outside the set's box.
TEST(SpatialIndex, TwoTreesMatchBruteForce) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-5.0f, 5.0f);
  std::vector<Eigen::Vector3f> pts(20000);
  for (auto& p : pts) p = {u(rng), u(rng) * 0.5f, u(rng) * 0.2f};
  const KdTreeIndex tree(pts);
  const BruteForceIndex brute(pts);
  std::uint32_t ia[12], ib[12];
  float da[12], db[12];
  for (int q = 0; q < 300; ++q) {
    const Eigen::Vector3f query(u(rng) * 1.5f, u(rng), u(rng));
    ASSERT_EQ(tree.knn(query, 12, ia, da), 12u);
    ASSERT_EQ(brute.knn(query, 12, ib, db), 12u);
    for (int k = 0; k < 12; ++k) EXPECT_EQ(ia[k], ib[k]) << "query " << q << " rank " << k;
    EXPECT_EQ(tree.radius_search(query, 0.3f), brute.radius_search(query, 0.3f));
  }
}

TEST(SpatialIndex, KnnRowsWithFewerPointsThanK) {
  const std::vector<Eigen::Vector3f> pts = {{0, 0, 0}, {1, 0, 0}};
  const KdTreeIndex tree(pts);
  std::vector<std::uint32_t> rows(2 * 5, 99), counts(2);
  tree.knn_rows(pts, 5, rows.data(), counts.data());
  EXPECT_EQ(counts, (std::vector<std::uint32_t>{2, 2}));
  EXPECT_EQ(rows[0], 0u);
  EXPECT_EQ(rows[1], 1u);
  EXPECT_EQ(rows[5], 1u);  // row 1 starts k = 5 entries in
  EXPECT_EQ(rows[6], 0u);
}

// The indexed points' rows start each search bounded by the previous point's neighbours: exact
// also where that bound is zero (stacks of identical points, more or fewer than k), where the
// previous point is far away (clusters far apart, so a leaf spans two), and where a leaf holds
// fewer points than k.
TEST(SpatialIndex, KnnRowsOfDuplicatesAndFarClusters) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<Eigen::Vector3f> pts;
  for (int cluster = 0; cluster < 40; ++cluster) {
    const Eigen::Vector3f centre(1000.0f * float(cluster % 7), 50.0f * float(cluster), 0.0f);
    const int stack = cluster % 3 == 0 ? 25 : cluster % 3 == 1 ? 4 : 0;  // identical points
    for (int i = 0; i < stack; ++i) pts.push_back(centre);
    for (int i = 0; i < 30 + cluster; ++i)
      pts.push_back(centre + Eigen::Vector3f(u(rng), u(rng), u(rng)));
  }
  std::shuffle(pts.begin(), pts.end(), rng);
  const KdTreeIndex tree(pts);
  for (const std::size_t k : {std::size_t{3}, std::size_t{10}, std::size_t{40}}) {
    SCOPED_TRACE(testing::Message() << "k " << k);
    expect_brute_force_rows(pts, tree, pts, k, 1);
  }
}

// The indexed points' rows list the leaves near each leaf once, within a reach taken from the
// previous leaf's neighbour distances: exact also where the density jumps between neighbouring
// leaves (dense patches beside sparse ones, so the reach falls short and points are searched
// again) and where whole leaves lie farther apart than any neighbour distance before them.
TEST(SpatialIndex, KnnRowsAcrossDensityJumps) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<Eigen::Vector3f> pts;
  for (int patch = 0; patch < 36; ++patch) {
    const float x0 = float(patch % 6), y0 = float(patch / 6);
    const int count = patch % 2 == 0 ? 600 : 6;  // 100 times denser
    for (int i = 0; i < count; ++i) pts.emplace_back(x0 + u(rng), y0 + u(rng), 0.001f * u(rng));
  }
  for (int i = 0; i < 20; ++i) pts.emplace_back(100.0f + 10.0f * float(i), 0.0f, 0.0f);
  std::shuffle(pts.begin(), pts.end(), rng);
  const KdTreeIndex tree(pts);
  // k = 10: the k-best list in registers; 11: unrolled in scratch; 2 and 33: the general one.
  for (const std::size_t k : {std::size_t{2}, std::size_t{10}, std::size_t{11}, std::size_t{33}}) {
    SCOPED_TRACE(testing::Message() << "k " << k);
    expect_brute_force_rows(pts, tree, pts, k, 1);
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
