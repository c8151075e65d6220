#pragma once
// The automatic voxel (and the flatness statistic the automatic extraction method needs) from a
// sample of the points that does not depend on their order or on how they are split: the
// points with the smallest hash of their coordinates. One process measures it on the whole
// cloud; the out-of-core path measures the same sample while streaming the input in batches
// (graph/chunked_reconstruction), so both choose the same voxel, bit for bit.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "nodes/search/spatial_index.h"
#include "runtime/point_cloud.h"

namespace meshflow {

/// Points of the sample (at most; all points when the cloud has fewer).
constexpr std::size_t kSpacingSamples = 2000;
/// Points of the scouts (SpacingSample::measure()), at least: a uniform subsample.
constexpr std::size_t kSpacingScouts = 64 * kSpacingSamples;

/// The sample's order among points: a 64-bit mix of the coordinates rounded to 1/1024 m
/// (points that close share it; a last-bit difference rarely changes it). Pure; O(1).
std::uint64_t spacing_sample_rank(const Eigen::Vector3f& p);

/// Streams points in any order and split (finite points only; call offer() on every batch,
/// then measure() on every batch): the kSpacingSamples points of smallest rank, the bounds,
/// and each sample's `neighbours` nearest points among everything measured. The results equal
/// those of one offer() and one measure() over the union, whatever the batches. Not
/// thread-safe; memory O(samples x neighbours).
class SpacingSample {
 public:
  /// `neighbours` >= 2 (the point itself counts: the second is its nearest other point).
  explicit SpacingSample(std::size_t neighbours = 2);

  /// First pass: keeps the lowest-ranked points of `points` with those kept so far and extends
  /// the bounds. Non-finite points are skipped. O(batch).
  void offer(const std::vector<Eigen::Vector3f>& points);
  /// Second pass: merges each sample's nearest points among `points` (`index` is built over
  /// them) into its list (and drops the scouts: see below). O(samples x neighbours x log batch).
  void measure(const std::vector<Eigen::Vector3f>& points, const SpatialIndex& index);
  /// The same without an index (a streamed batch; no kd-tree over it): a point can join a
  /// sample's list only within its reach, the nearer of its `neighbours`-th nearest scout (the
  /// scouts: a subsample of every offered point at a stride, kept by offer(), a subset of the
  /// points, so never nearer than the true neighbour) and its farthest kept neighbour. The points
  /// within reach are found through grids over the samples whose reach touches the batch's box (one
  /// grid per scale of reach, each sample in the <= 8 cells its ball touches), their squared
  /// distances computed as the kd-tree computes them; each sample keeps its `neighbours` nearest of
  /// all points measured, ties by the points' bits, as measure(points, index) over the union. The
  /// first call measures the scouts (a kd-tree over them) and drops them. Parallel over the
  /// points; O(batch x grids + scouts log scouts once).
  void measure(const std::vector<Eigen::Vector3f>& points);

  /// Joins another sample's first pass (over other points) into this one: as if this one had
  /// been offered them too. O(samples).
  void merge_offered(const SpacingSample& other);
  /// Joins another copy's second pass: `other` must hold the same samples (a copy of this one
  /// made after the first pass) measured over other points. O(samples x neighbours).
  void merge_measured(const SpacingSample& other);

  /// The sample as bytes (bounds, samples and their neighbours, scouts) and back, for processes
  /// that join their parts' samples (MPI ranks). from_bytes() throws meshflow::Error naming
  /// `source` on a short or inconsistent message. O(samples x neighbours).
  std::vector<unsigned char> to_bytes() const;
  /// The sample to_bytes() gave (see above).
  static SpacingSample from_bytes(const std::vector<unsigned char>& bytes,
                                  const std::string& source);

  /// factor x the median distance from a sample to its nearest other point, and at least 1/2000
  /// of the bounds' diagonal (suggest_voxel_size's rule). 0.05 with fewer than two points;
  /// 0 when all points coincide. Metres.
  float voxel_size(float factor = 3.0f) const;
  /// The median, over samples with at least 3 neighbours, of their neighbourhoods' plane-fit
  /// variation (smallest covariance eigenvalue over the sum: 0 on a plane, 1/3 at most), as
  /// NormalsConfig::clean_variation and noisy_variation judge it; 1 when none.
  float median_variation() const;
  /// Points per square metre of surface around a typical point: the median, over samples with
  /// at least 3 neighbours (2 besides itself) at a positive distance, of m / (pi r^2), r the
  /// distance to the farthest of its m other neighbours (a surface sampled with density rho
  /// holds about rho pi r^2 points within r). 0 when no sample qualifies. O(samples).
  float surface_density() const;

  std::size_t size() const { return samples_.size(); }  ///< samples kept
  /// The bounds of every point offered so far (metres).
  const Eigen::AlignedBox3f& bounds() const { return bounds_; }

 private:
  struct Sample {
    std::uint64_t rank;
    Eigen::Vector3f position;
    std::vector<std::pair<float, Eigen::Vector3f>> nearest;  // (squared distance, point)
  };
  void keep_lowest();
  void keep_nearest(std::vector<std::pair<float, Eigen::Vector3f>>& nearest) const;
  void offer_scouts(const std::vector<Eigen::Vector3f>& points);
  void thin_scouts(std::size_t coming);
  void measure_within_reach(const std::vector<Eigen::Vector3f>& points,
                            const std::vector<float>& reach2);

  std::size_t neighbours_;
  std::vector<Sample> samples_;
  Eigen::AlignedBox3f bounds_;
  /// Every scout_stride_-th finite point offered (kSpacingScouts to twice as many): what
  /// measure() bounds each sample's reach by; dropped once it has.
  std::vector<Eigen::Vector3f> scouts_;
  std::size_t scout_stride_ = 1, scout_skip_ = 0;
  std::vector<float> scout_reach2_;  ///< per sample, once measured: its neighbours-th scout
};

/// One process's automatic voxel: SpacingSample over `cloud` (index over cloud.positions).
float auto_voxel_size(const PointCloud& cloud, const SpatialIndex& index, float factor = 3.0f);

}  // namespace meshflow
