#pragma once
// Spatial search over a point set: one small interface, a bucket kd-tree behind it
// (kd_tree::BucketTree), and a brute-force implementation that serves as the test oracle.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

namespace meshflow {

/// Nearest-neighbour queries over a fixed point set. Implementations do not own the points:
/// the caller keeps `points` alive and unchanged while the index is used.
/// All query methods are const and safe to call concurrently from many threads.
class SpatialIndex {
 public:
  virtual ~SpatialIndex() = default;

  /// Writes the (up to) k nearest points to q, closest first, as indices and squared
  /// distances (m^2); returns how many were found (min(k, size())). Ties break arbitrarily
  /// but deterministically. O(log n + k) expected for the kd-tree, O(n) brute force.
  virtual std::size_t knn(const Eigen::Vector3f& q, std::size_t k, std::uint32_t* indices,
                          float* squared_distances) const = 0;

  /// Indices of all points within `radius` metres of q, closest first.
  virtual std::vector<std::uint32_t> radius_search(const Eigen::Vector3f& q,
                                                   float radius) const = 0;

  /// knn() of every point of `queries` (finite, metres): row q, indices[q k ...], holds
  /// counts[q] indices exactly as knn(queries[q], k) writes them (squared distances dropped).
  /// `indices` holds queries.size() * k entries, `counts` queries.size(). Parallel over the
  /// queries; the result does not depend on the thread count. This implementation calls knn();
  /// the kd-tree answers the indexed points themselves faster (see KdTreeIndex). O(m knn()).
  virtual void knn_rows(const std::vector<Eigen::Vector3f>& queries, std::size_t k,
                        std::uint32_t* indices, std::uint32_t* counts) const;

  /// Number of indexed points.
  virtual std::size_t size() const = 0;
};

/// Exact search over a kd-tree (kd_tree::BucketTree: median splits, tight node boxes, leaves of up
/// to 32 points searched 8 at a time), built in parallel over subtrees. Build O(n log n).
class KdTreeIndex final : public SpatialIndex {
 public:
  /// Builds the tree over `points` (finite, metres), which must outlive the index unchanged.
  explicit KdTreeIndex(const std::vector<Eigen::Vector3f>& points);
  ~KdTreeIndex() override;
  std::size_t knn(const Eigen::Vector3f& q, std::size_t k, std::uint32_t* indices,
                  float* squared_distances) const override;
  std::vector<std::uint32_t> radius_search(const Eigen::Vector3f& q, float radius) const override;
  /// SpatialIndex::knn_rows(); for the indexed points themselves (the same vector) each search
  /// starts in the point's own leaf, bounded by the previous point's neighbours
  /// (BucketTree::knn_of_points()).
  void knn_rows(const std::vector<Eigen::Vector3f>& queries, std::size_t k, std::uint32_t* indices,
                std::uint32_t* counts) const override;
  /// Number of indexed points.
  std::size_t size() const override { return size_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::size_t size_;
};

/// Exhaustive search; the oracle for tests. O(n) per query.
class BruteForceIndex final : public SpatialIndex {
 public:
  /// Searches `points`, which must outlive the index unchanged. O(1).
  explicit BruteForceIndex(const std::vector<Eigen::Vector3f>& points) : points_(points) {}
  std::size_t knn(const Eigen::Vector3f& q, std::size_t k, std::uint32_t* indices,
                  float* squared_distances) const override;
  std::vector<std::uint32_t> radius_search(const Eigen::Vector3f& q, float radius) const override;
  /// Number of indexed points.
  std::size_t size() const override { return points_.size(); }

 private:
  const std::vector<Eigen::Vector3f>& points_;
};

}  // namespace meshflow
