// The automatic voxel's sample (nodes/voxelize/spacing_sample.h): the same voxel, bit for bit,
// whatever the order of the points and however they are split into batches (the out-of-core
// path streams them), and the spacing it measures is the brute-force one.

#include "nodes/voxelize/spacing_sample.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "nodes/voxelize/voxelize.h"
#include "runtime/error.h"

namespace meshflow {
namespace {

// Points on a wavy 20 m x 20 m sheet, jittered, with a few duplicates.
PointCloud wavy_sheet(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 20.0f);
  PointCloud cloud;
  for (std::size_t i = 0; i < n; ++i) {
    const float x = u(rng), y = u(rng);
    cloud.positions.emplace_back(x, y, 0.5f * std::sin(0.7f * x) * std::cos(0.4f * y));
  }
  for (std::size_t i = 0; i < n / 100; ++i) cloud.positions.push_back(cloud.positions[i * 7]);
  return cloud;
}

// `cloud`'s positions cut into batches of `batch` points, in order.
std::vector<std::vector<Eigen::Vector3f>> batches(const PointCloud& cloud, std::size_t batch) {
  std::vector<std::vector<Eigen::Vector3f>> pieces;
  for (std::size_t at = 0; at < cloud.size(); at += batch)
    pieces.emplace_back(
        cloud.positions.begin() + static_cast<std::ptrdiff_t>(at),
        cloud.positions.begin() + static_cast<std::ptrdiff_t>(std::min(cloud.size(), at + batch)));
  return pieces;
}

// SpacingSample fed `cloud` in batches of `batch` points, both passes.
SpacingSample streamed(const PointCloud& cloud, std::size_t batch, std::size_t neighbours) {
  SpacingSample sample(neighbours);
  const auto pieces = batches(cloud, batch);
  for (const auto& piece : pieces) sample.offer(piece);
  for (const auto& piece : pieces) {
    const KdTreeIndex index(piece);
    sample.measure(piece, index);
  }
  return sample;
}

// The same with measure()'s own search (a kd-tree over the first batch only).
SpacingSample streamed_without_index(const PointCloud& cloud, std::size_t batch,
                                     std::size_t neighbours) {
  SpacingSample sample(neighbours);
  const auto pieces = batches(cloud, batch);
  for (const auto& piece : pieces) sample.offer(piece);
  for (const auto& piece : pieces) sample.measure(piece);
  return sample;
}

TEST(SpacingSample, MeasuresWithoutAnIndexAsTheKdTreeDoes) {
  // Shuffled, and sorted along x (each batch is one strip); every sample's neighbours as one
  // kd-tree over the whole cloud finds them, bit for bit.
  // The large one has more points than the scouts keep: their reach is wider than the
  // neighbours' until the sample's own strip arrives.
  const auto by_x = [](PointCloud cloud) {
    std::sort(cloud.positions.begin(), cloud.positions.end(),
              [](const Eigen::Vector3f& a, const Eigen::Vector3f& b) { return a.x() < b.x(); });
    return cloud;
  };
  const PointCloud shuffled = wavy_sheet(60000, 5), sorted = by_x(shuffled);
  const PointCloud large = by_x(wavy_sheet(600000, 6));
  for (const PointCloud* cloud : {&shuffled, &sorted, &large}) {
    const KdTreeIndex index(cloud->positions);
    SpacingSample whole(10);
    whole.offer(cloud->positions);
    whole.measure(cloud->positions, index);
    const SpacingSample batches =
        streamed_without_index(*cloud, cloud->size() > 100000 ? 50000 : 7000, 10);
    EXPECT_EQ(batches.to_bytes(), whole.to_bytes());
    EXPECT_EQ(batches.voxel_size(), whole.voxel_size());
    EXPECT_EQ(batches.median_variation(), whole.median_variation());
  }
}

TEST(SpacingSample, SameVoxelWhateverTheOrderAndTheBatches) {
  const PointCloud cloud = wavy_sheet(60000, 3);
  const KdTreeIndex index(cloud.positions);
  const float whole = auto_voxel_size(cloud, index);
  ASSERT_GT(whole, 0.0f);
  PointCloud shuffled = cloud;
  std::shuffle(shuffled.positions.begin(), shuffled.positions.end(), std::mt19937(9));
  for (const std::size_t batch : {std::size_t{997}, std::size_t{20000}, std::size_t{100000}}) {
    EXPECT_EQ(streamed(cloud, batch, 2).voxel_size(), whole) << "batches of " << batch;
    EXPECT_EQ(streamed(shuffled, batch, 2).voxel_size(), whole) << "shuffled, batches of " << batch;
  }
  const KdTreeIndex shuffled_index(shuffled.positions);
  EXPECT_EQ(auto_voxel_size(shuffled, shuffled_index), whole);
  // The median-variation statistic does not depend on the split either.
  EXPECT_EQ(streamed(cloud, 997, 10).median_variation(),
            streamed(shuffled, 20000, 10).median_variation());
}

// As MPI ranks join them: two halves sampled apart, joined through bytes, then each half
// measured by a copy of the joined sample and the measures joined again.
TEST(SpacingSample, HalvesJoinedThroughBytesGiveTheWholeVoxel) {
  const PointCloud cloud = wavy_sheet(30000, 11);
  const KdTreeIndex index(cloud.positions);
  const std::size_t half = cloud.size() / 2;
  const std::vector<Eigen::Vector3f> a(cloud.positions.begin(),
                                       cloud.positions.begin() + static_cast<std::ptrdiff_t>(half)),
      b(cloud.positions.begin() + static_cast<std::ptrdiff_t>(half), cloud.positions.end());
  SpacingSample first(10), second(10);
  first.offer(a);
  second.offer(b);
  first.merge_offered(SpacingSample::from_bytes(second.to_bytes(), "rank 1"));
  SpacingSample copy = SpacingSample::from_bytes(first.to_bytes(), "rank 0");
  const KdTreeIndex index_a(a), index_b(b);
  first.measure(a, index_a);
  copy.measure(b, index_b);
  first.merge_measured(SpacingSample::from_bytes(copy.to_bytes(), "rank 1"));
  EXPECT_EQ(first.voxel_size(), auto_voxel_size(cloud, index));
  EXPECT_EQ(first.median_variation(), streamed(cloud, 4000, 10).median_variation());
  std::vector<unsigned char> cut = first.to_bytes();
  cut.resize(cut.size() / 2);
  EXPECT_THROW(SpacingSample::from_bytes(cut, "cut"), Error);
}

TEST(SpacingSample, MeasuresTheNearestNeighbourSpacingOfTheSample) {
  const PointCloud cloud = wavy_sheet(20000, 5);
  const KdTreeIndex index(cloud.positions);
  SpacingSample sample;
  sample.offer(cloud.positions);
  sample.measure(cloud.positions, index);
  ASSERT_EQ(sample.size(), kSpacingSamples);
  // Brute force: the samples are the lowest-ranked points; each one's nearest other point.
  std::vector<std::pair<std::uint64_t, std::size_t>> ranked;
  for (std::size_t i = 0; i < cloud.size(); ++i)
    ranked.emplace_back(spacing_sample_rank(cloud.positions[i]), i);
  std::sort(ranked.begin(), ranked.end());
  std::vector<float> spacing;
  for (std::size_t s = 0; s < kSpacingSamples; ++s) {
    const Eigen::Vector3f& p = cloud.positions[ranked[s].second];
    float best = std::numeric_limits<float>::infinity();
    bool self = false;
    for (const Eigen::Vector3f& q : cloud.positions) {
      const float d2 = (q - p).squaredNorm();
      if (d2 == 0.0f && !self) {
        self = true;  // the point itself (a duplicate counts as its nearest other point)
        continue;
      }
      best = std::min(best, d2);
    }
    spacing.push_back(std::sqrt(best));
  }
  std::nth_element(spacing.begin(), spacing.begin() + kSpacingSamples / 2, spacing.end());
  EXPECT_FLOAT_EQ(sample.voxel_size(3.0f), 3.0f * spacing[kSpacingSamples / 2]);
  // About the stride sample's estimate (suggest_voxel_size): the same statistic.
  EXPECT_NEAR(sample.voxel_size(), suggest_voxel_size(cloud, index), 0.1 * sample.voxel_size());
}

TEST(SpacingSample, SurfaceDensityIsThePointsPerSquareMetre) {
  // Uniform on a 20 m x 20 m (gently wavy: 2 % more area) sheet: n / 400 points per m^2,
  // streamed in batches as the out-of-core path measures it.
  for (const std::size_t n : {20000u, 80000u}) {
    const PointCloud cloud = wavy_sheet(n, 11);
    const double truth = static_cast<double>(n) / 400.0;
    EXPECT_NEAR(streamed(cloud, 7000, 10).surface_density(), truth, 0.1 * truth) << n;
  }
  EXPECT_EQ(SpacingSample(10).surface_density(), 0.0f) << "no sample: no density";
}

TEST(SpacingSample, MedianVariationTellsASurfaceFromAVolume) {
  const PointCloud sheet = wavy_sheet(20000, 7);
  EXPECT_LT(streamed(sheet, 5000, 10).median_variation(), 0.005f);
  PointCloud volume;
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int i = 0; i < 20000; ++i) volume.positions.emplace_back(u(rng), u(rng), u(rng));
  EXPECT_GT(streamed(volume, 5000, 10).median_variation(), 0.1f);
  EXPECT_EQ(SpacingSample(10).median_variation(), 1.0f) << "no sample: no evidence of a surface";
}

TEST(SpacingSample, FewPointsAndCoincidingPoints) {
  PointCloud one;
  one.positions = {Eigen::Vector3f(1, 2, 3)};
  const KdTreeIndex one_index(one.positions);
  EXPECT_EQ(auto_voxel_size(one, one_index), 0.05f) << "suggest_voxel_size's fallback";
  PointCloud same;
  same.positions.assign(50, Eigen::Vector3f(1, 2, 3));
  const KdTreeIndex same_index(same.positions);
  EXPECT_EQ(auto_voxel_size(same, same_index), 0.0f) << "no spacing, no extent";
}

}  // namespace
}  // namespace meshflow
