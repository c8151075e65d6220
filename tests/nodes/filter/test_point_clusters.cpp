#include "nodes/filter/point_clusters.h"

#include <gtest/gtest.h>

#include <random>

#include "nodes/synthetic/closed_objects.h"
#include "nodes/synthetic/object_scan.h"
#include "runtime/error.h"
#include "test_support.h"

namespace meshflow {
namespace {

// Brute-force oracle: components of the graph joining every pair closer than `radius`.
std::vector<std::uint32_t> all_pairs_clusters(const PointCloud& cloud, float radius,
                                              std::size_t min_points) {
  const std::size_t n = cloud.size();
  std::vector<int> label(n, -1);
  std::vector<std::size_t> size;
  for (std::size_t s = 0; s < n; ++s) {
    if (label[s] >= 0) continue;
    const int id = static_cast<int>(size.size());
    size.push_back(0);
    std::vector<std::size_t> stack{s};
    label[s] = id;
    while (!stack.empty()) {
      const std::size_t i = stack.back();
      stack.pop_back();
      ++size.back();
      for (std::size_t j = 0; j < n; ++j)
        if (label[j] < 0 && (cloud.positions[i] - cloud.positions[j]).norm() <= radius) {
          label[j] = id;
          stack.push_back(j);
        }
    }
  }
  std::vector<std::uint32_t> keep;
  for (std::size_t i = 0; i < n; ++i)
    if (size[static_cast<std::size_t>(label[i])] >= min_points)
      keep.push_back(static_cast<std::uint32_t>(i));
  return keep;
}

TEST(PointClusters, MatchesAllPairsRadiusComponents) {
  // Random points, plus dense short rows (each point's 8 nearest neighbours on its own row, as
  // on a scan line seen at a grazing angle) whose rows lie within the radius of each other.
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  PointCloud cloud;
  for (int i = 0; i < 1500; ++i) cloud.positions.emplace_back(u(rng), u(rng), u(rng));
  for (int row = 0; row < 3; ++row)
    for (int i = 0; i < 12; ++i)
      cloud.positions.emplace_back(2.0f + 0.001f * static_cast<float>(i),
                                   0.05f * static_cast<float>(row), 0.0f);
  const KdTreeIndex index(cloud.positions);
  ClusterConfig config;
  config.link_radius = 0.07f;
  for (std::size_t min_points : {2u, 3u, 5u, 20u}) {
    config.min_points = min_points;
    ClusterCounts counts;
    const std::vector<std::uint32_t> got = surface_cluster_indices(cloud, index, config, &counts);
    EXPECT_EQ(got, all_pairs_clusters(cloud, config.link_radius, min_points)) << min_points;
    EXPECT_EQ(got.size() + counts.isolated + counts.sparse, cloud.size());
    EXPECT_GT(counts.isolated, 0u);
  }
}

// A cloud wider than the grid's packed cells (2^21 per axis: a stray point a hundred thousand
// radii away) is linked through the nearest neighbours instead: the same components.
TEST(PointClusters, WideCloudsGiveTheSameComponents) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  PointCloud cloud;
  for (int i = 0; i < 800; ++i) cloud.positions.emplace_back(u(rng), u(rng), u(rng));
  for (int i = 0; i < 30; ++i)  // a far cluster of 30 points, linked along a line
    cloud.positions.emplace_back(50000.0f + 0.02f * static_cast<float>(i), 0.0f, 0.0f);
  cloud.positions.emplace_back(-50000.0f, 0.0f, 0.0f);  // isolated
  const KdTreeIndex index(cloud.positions);
  ClusterConfig config;
  config.link_radius = 0.07f;
  for (std::size_t min_points : {2u, 20u, 40u}) {
    config.min_points = min_points;
    ClusterCounts counts;
    const std::vector<std::uint32_t> got = surface_cluster_indices(cloud, index, config, &counts);
    EXPECT_EQ(got, all_pairs_clusters(cloud, config.link_radius, min_points)) << min_points;
    EXPECT_EQ(got.size() + counts.isolated + counts.sparse, cloud.size());
    EXPECT_GE(counts.isolated, 1u);
  }
}

// Cells spread so far (2^20 cells on every axis: 63 bits of cell offsets) that the sort keys
// and the points' indices do not fit in 64 bits: the grid sorts pairs instead; the same
// components, at 1, 2 and 4 threads.
TEST(PointClusters, WideGridKeysGiveTheSameComponents) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  PointCloud cloud;
  for (int i = 0; i < 700; ++i) cloud.positions.emplace_back(u(rng), u(rng), u(rng));
  const float far = 40000.0f;  // 40 km: 10^6 cells of 4 cm, within the grid's 2^21
  for (int i = 0; i < 25; ++i)
    cloud.positions.emplace_back(far + 0.03f * static_cast<float>(i), far, far);
  cloud.positions.emplace_back(-far, far, -far);  // isolated
  const KdTreeIndex index(cloud.positions);
  ClusterConfig config;
  config.link_radius = 0.07f;
  for (std::size_t min_points : {2u, 20u, 30u}) {
    config.min_points = min_points;
    const auto run = [&] { return surface_cluster_indices(cloud, index, config); };
    const std::vector<std::uint32_t> expected =
        all_pairs_clusters(cloud, config.link_radius, min_points);
    EXPECT_EQ(test::with_threads(1, run), expected) << min_points;
    EXPECT_EQ(test::with_threads(2, run), expected) << min_points;
    EXPECT_EQ(test::with_threads(4, run), expected) << min_points;
  }
}

TEST(PointClusters, DropsScatteredOutliersKeepsTheScannedSurface) {
  const synthetic::ClosedObject object = synthetic::sphere_object();
  synthetic::ObjectScanConfig sc;
  sc.outlier_fraction = 0.005f;
  const synthetic::ObjectScan scan = synthetic::scan_object(object, sc);
  const std::size_t surface = scan.cloud.size() - scan.outliers;
  ASSERT_GT(scan.outliers, 100u);
  const KdTreeIndex index(scan.cloud.positions);
  ClusterConfig config;
  config.link_radius = 0.02f * object.diagonal();  // 2 voxels of 1 % of the diagonal
  ClusterCounts counts;
  const std::vector<std::uint32_t> keep =
      surface_cluster_indices(scan.cloud, index, config, &counts);
  std::size_t surface_kept = 0, far_kept = 0, far = 0;
  std::vector<std::uint8_t> kept(scan.cloud.size(), 0);
  for (std::uint32_t i : keep) kept[i] = 1;
  for (std::size_t i = 0; i < scan.cloud.size(); ++i) {
    if (i < surface) {
      surface_kept += kept[i];
      // A dropped point's cluster is small, so it has few points within a link.
      if (!kept[i]) {
        EXPECT_LT(index.radius_search(scan.cloud.positions[i], config.link_radius).size(),
                  config.min_points);
      }
      continue;
    }
    // An outlier farther than a link from the surface can only join other outliers.
    if (object.distance(scan.cloud.positions[i]) > config.link_radius) {
      ++far;
      far_kept += kept[i];
    }
  }
  // Only the last rows at grazing angles, sparser than a link, go.
  EXPECT_GT(surface_kept, surface - surface / 200) << "of " << surface << " surface points";
  EXPECT_GT(far, scan.outliers / 2);
  EXPECT_EQ(far_kept, 0u) << "of " << far << " outliers away from the surface";
  EXPECT_EQ(counts.isolated + counts.sparse, scan.cloud.size() - keep.size());
  EXPECT_EQ(counts.clusters, 1u) << "one sphere";
}

TEST(PointClusters, KeepsThinStructures) {
  // A pole (one line of points, spacing 0.3 link) and a thin plate sampled on both faces,
  // far apart: both stay whole.
  PointCloud cloud = synthetic::thin_plate_object().sample(20000, 0.0f, 3);
  const float link = 0.012f;  // 2 voxels of 0.6 cm
  const std::size_t pole_points = 60;
  for (std::size_t i = 0; i < pole_points; ++i)
    cloud.positions.emplace_back(2.0f, 0.0f, 0.3f * link * static_cast<float>(i));
  cloud.normals.clear();
  const KdTreeIndex index(cloud.positions);
  ClusterConfig config;
  config.link_radius = link;
  ClusterCounts counts;
  const std::vector<std::uint32_t> keep = surface_cluster_indices(cloud, index, config, &counts);
  EXPECT_EQ(keep.size(), cloud.size());
  EXPECT_EQ(counts.clusters, 2u);
}

TEST(PointClusters, SameResultForOneAndTwoThreads) {
  synthetic::ObjectScanConfig sc;
  sc.outlier_fraction = 0.005f;
  const synthetic::ObjectScan scan = synthetic::scan_object(synthetic::torus_object(), sc);
  const KdTreeIndex index(scan.cloud.positions);
  ClusterConfig config;
  config.link_radius = 0.02f;
  const auto run = [&] { return surface_cluster_indices(scan.cloud, index, config); };
  EXPECT_EQ(test::with_threads(1, run), test::with_threads(2, run));
}

TEST(PointClusters, OffKeepsAllAndBadRadiusIsAnError) {
  PointCloud cloud;
  cloud.positions = {{0, 0, 0}, {5, 0, 0}, {0, 5, 0}};
  const KdTreeIndex index(cloud.positions);
  ClusterConfig config;
  config.min_points = 0;
  EXPECT_EQ(surface_cluster_indices(cloud, index, config).size(), 3u);
  config.min_points = 2;
  config.link_radius = 0.0f;
  EXPECT_THROW(surface_cluster_indices(cloud, index, config), Error);
  config.link_radius = 1.0f;
  ClusterCounts counts;
  EXPECT_TRUE(surface_cluster_indices(cloud, index, config, &counts).empty());
  EXPECT_EQ(counts.isolated, 3u);
}

}  // namespace
}  // namespace meshflow
