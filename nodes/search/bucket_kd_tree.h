#pragma once
// An exact kd-tree over a fixed point set whose leaves ("buckets" of up to kLeafSize points) are
// stored contiguously as x, y and z arrays, searched 8 points at a time. Behind KdTreeIndex.

#include <Eigen/Core>
#include <cstdint>
#include <utility>
#include <vector>

#include "runtime/default_init.h"

namespace meshflow::kd_tree {

/// Balanced kd-tree: each node splits its points at the median of its bounding box's longest
/// axis; every node keeps the tight box of its points, so a search skips the empty space of
/// scans. Searches return exactly the brute-force answer: squared distances computed as
/// ((dx dx + dy dy) + dz dz) in float, ties broken by the smaller index, whatever the tree's
/// shape. Queries are const and safe to call from many threads at once.
class BucketTree {
 public:
  static constexpr std::uint32_t kLeafSize = 32;

  /// Builds the tree over a copy of `points` (finite, metres; fewer than 2^32 - 8). Parallel
  /// over subtrees; the tree does not depend on the thread count. O(n log n).
  explicit BucketTree(const std::vector<Eigen::Vector3f>& points);

  /// The (up to) k nearest points to q, closest first, as indices and squared distances;
  /// returns how many (min(k, size())). O(log n + k) expected.
  std::size_t knn(const Eigen::Vector3f& q, std::size_t k, std::uint32_t* indices,
                  float* squared_distances) const;

  /// Every point within squared distance `squared_radius` of q (inclusive), as (index, squared
  /// distance) pairs in no particular order, appended to `hits`.
  void radius(const Eigen::Vector3f& q, float squared_radius,
              std::vector<std::pair<std::uint32_t, float>>& hits) const;

  /// knn() of every indexed point (`points`: the ones the tree was built over, unchanged): row
  /// i (indices + i * stride) gets the k nearest points of point i, counts[i] how many.
  /// Queries run leaf by leaf: the leaves near each leaf are listed once and each of its
  /// points scans its own and those within its current k-th distance (searched again from the
  /// root when that ends beyond the list's reach); parallel over blocks of leaves; the result
  /// does not depend on the thread count. O(n (log n + k)).
  void knn_of_points(const std::vector<Eigen::Vector3f>& points, std::size_t k, std::size_t stride,
                     std::uint32_t* indices, std::uint32_t* counts) const;

  /// Number of indexed points.
  std::size_t size() const { return ids_.size(); }

  struct Node {
    float lo[4], hi[4];       // the tight bounding box of the node's points (x, y, z, 0)
    std::uint32_t begin = 0;  // leaves: first point (leaf order)
    std::uint32_t count = 0;  // leaves: number of points; 0 for an inner node or an unused slot
  };

 private:
  struct Item;  // a point and its index, while the tree is built
  void build(std::size_t node, std::uint32_t begin, std::uint32_t end, Item* items);

  // Nodes numbered as a heap: the children of node i are 2 i + 1 and 2 i + 2.
  std::vector<Node> nodes_;
  // Points in leaf order, followed by 8 slots of padding (a leaf's last block of 8 reads past
  // its end), and each one's index in the caller's set.
  UninitVector<float> xs_, ys_, zs_;
  UninitVector<std::uint32_t> ids_;
  std::vector<std::uint32_t> leaves_;  // leaf nodes in leaf order
};

}  // namespace meshflow::kd_tree
