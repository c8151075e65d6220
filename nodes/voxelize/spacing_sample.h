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
  /// them) into its list. O(samples x neighbours x log batch).
  void measure(const std::vector<Eigen::Vector3f>& points, const SpatialIndex& index);

  /// Joins another sample's first pass (over other points) into this one: as if this one had
  /// been offered them too. O(samples).
  void merge_offered(const SpacingSample& other);
  /// Joins another copy's second pass: `other` must hold the same samples (a copy of this one
  /// made after the first pass) measured over other points. O(samples x neighbours).
  void merge_measured(const SpacingSample& other);

  /// The sample as bytes (bounds, samples and their neighbours) and back, for processes that
  /// join their parts' samples (MPI ranks). from_bytes() throws meshflow::Error naming
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

  std::size_t neighbours_;
  std::vector<Sample> samples_;
  Eigen::AlignedBox3f bounds_;
};

/// One process's automatic voxel: SpacingSample over `cloud` (index over cloud.positions).
float auto_voxel_size(const PointCloud& cloud, const SpatialIndex& index, float factor = 3.0f);

}  // namespace meshflow
