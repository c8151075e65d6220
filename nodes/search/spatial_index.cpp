#include "nodes/search/spatial_index.h"

#include <nanoflann.hpp>

#include <algorithm>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <utility>

namespace meshflow {

// Named, not anonymous: KdTreeIndex::Impl (external linkage) holds these types, and GCC warns
// (-Wsubobject-linkage) when such a member's type lives in an anonymous namespace of a file that
// a unity build includes.
namespace kd_tree {

// nanoflann reads the points through this adaptor: packed xyz floats, not copied.
struct PackedPoints {
  const Eigen::Vector3f* points = nullptr;
  std::size_t count = 0;
  std::size_t kdtree_get_point_count() const { return count; }
  float kdtree_get_pt(std::uint32_t i, std::size_t dim) const { return points[i].data()[dim]; }
  template <class Box>
  bool kdtree_get_bbox(Box& /*box*/) const {
    return false;  // the tree computes the bounds
  }
};

using Metric = nanoflann::L2_Simple_Adaptor<float, PackedPoints, float, std::uint32_t>;
using Tree = nanoflann::KDTreeSingleIndexAdaptor<Metric, PackedPoints, 3, std::uint32_t>;

}  // namespace kd_tree

namespace {

// The next float above x >= 0 (x itself for infinity): std::nextafter without libm's call, which
// cost 3 % of a reconstruction when made on every improvement of a k-nearest result.
float next_float_up(float x) {
  if (!(x < std::numeric_limits<float>::max())) return x;
  std::uint32_t bits = 0;
  std::memcpy(&bits, &x, sizeof bits);
  bits += 1;  // non-negative floats order like their bit patterns
  std::memcpy(&x, &bits, sizeof bits);
  return x;
}

// The k smallest (squared distance, index) pairs, written straight into the caller's arrays (no
// heap allocation per query). Ties break by the smaller index whatever order the tree visits
// points in: the bound handed to the tree is the next float above the k-th distance, so a point
// at exactly that distance still reaches add_point, which compares indices. The result is
// therefore the brute-force answer, independent of the tree's shape.
class KnnResult {
 public:
  KnnResult(std::size_t k, std::uint32_t* indices, float* dists)
      : k_(k), indices_(indices), dists_(dists) {}

  // nanoflann's result-set interface (its names).
  float worstDist() const {  // NOLINT(readability-identifier-naming)
    return bound_;
  }
  bool addPoint(float dist, std::uint32_t idx) {  // NOLINT(readability-identifier-naming)
    if (count_ == k_ &&
        !(dist < dists_[k_ - 1] || (dist == dists_[k_ - 1] && idx < indices_[k_ - 1]))) {
      return true;
    }
    std::size_t i = count_ < k_ ? count_++ : k_ - 1;
    for (; i > 0 && (dists_[i - 1] > dist || (dists_[i - 1] == dist && indices_[i - 1] > idx));
         --i) {
      dists_[i] = dists_[i - 1];
      indices_[i] = indices_[i - 1];
    }
    dists_[i] = dist;
    indices_[i] = idx;
    if (count_ == k_) bound_ = next_float_up(dists_[k_ - 1]);
    return true;  // keep searching: a closer point may remain
  }
  bool full() const { return count_ == k_; }
  std::size_t size() const { return count_; }

 private:
  std::size_t k_;
  std::uint32_t* indices_;
  float* dists_;
  float bound_ = std::numeric_limits<float>::infinity();
  std::size_t count_ = 0;
};

// Every point within `radius` (squared distance <= radius^2, as the brute-force oracle), in the
// order the tree finds them.
class RadiusResult {
 public:
  RadiusResult(float squared_radius, std::vector<std::pair<std::uint32_t, float>>& hits)
      : squared_radius_(squared_radius), bound_(next_float_up(squared_radius)), hits_(hits) {}
  // nanoflann's result-set interface (its names).
  float worstDist() const {  // NOLINT(readability-identifier-naming)
    return bound_;
  }
  bool addPoint(float dist, std::uint32_t idx) {  // NOLINT(readability-identifier-naming)
    if (dist <= squared_radius_) hits_.emplace_back(idx, dist);
    return true;
  }
  bool full() const { return true; }

 private:
  float squared_radius_;
  float bound_;
  std::vector<std::pair<std::uint32_t, float>>& hits_;
};

}  // namespace

struct KdTreeIndex::Impl {
  kd_tree::PackedPoints points;
  kd_tree::Tree tree;
  explicit Impl(const std::vector<Eigen::Vector3f>& cloud)
      : points{cloud.data(), cloud.size()},
        tree(3, points, nanoflann::KDTreeSingleIndexAdaptorParams(/*leaf_max_size=*/10)) {}
};

KdTreeIndex::KdTreeIndex(const std::vector<Eigen::Vector3f>& points) : size_(points.size()) {
  if (points.size() >= std::numeric_limits<std::uint32_t>::max())
    throw std::length_error("KdTreeIndex: more than 2^32 - 1 points");
  if (points.empty()) return;
  impl_ = std::make_unique<Impl>(points);  // builds the tree
}

KdTreeIndex::~KdTreeIndex() = default;

std::size_t KdTreeIndex::knn(const Eigen::Vector3f& q, std::size_t k, std::uint32_t* indices,
                             float* squared_distances) const {
  k = std::min(k, size_);
  if (k == 0) return 0;
  KnnResult result(k, indices, squared_distances);
  impl_->tree.findNeighbors(result, q.data(), nanoflann::SearchParams(0, 0.0f, false));
  return result.size();
}

std::vector<std::uint32_t> KdTreeIndex::radius_search(const Eigen::Vector3f& q,
                                                      float radius) const {
  if (size_ == 0) return {};
  std::vector<std::pair<std::uint32_t, float>> hits;
  RadiusResult result(radius * radius, hits);
  impl_->tree.findNeighbors(result, q.data(), nanoflann::SearchParams(0, 0.0f, false));
  std::sort(hits.begin(), hits.end(), [](const auto& a, const auto& b) {
    return a.second < b.second || (a.second == b.second && a.first < b.first);
  });
  std::vector<std::uint32_t> out(hits.size());
  for (std::size_t i = 0; i < hits.size(); ++i) out[i] = hits[i].first;
  return out;
}

std::size_t BruteForceIndex::knn(const Eigen::Vector3f& q, std::size_t k, std::uint32_t* indices,
                                 float* squared_distances) const {
  std::vector<std::pair<float, std::uint32_t>> all(points_.size());
  for (std::size_t i = 0; i < points_.size(); ++i) {
    all[i] = {(points_[i] - q).squaredNorm(), static_cast<std::uint32_t>(i)};
  }
  k = std::min(k, all.size());
  std::partial_sort(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(k), all.end());
  for (std::size_t i = 0; i < k; ++i) {
    squared_distances[i] = all[i].first;
    indices[i] = all[i].second;
  }
  return k;
}

std::vector<std::uint32_t> BruteForceIndex::radius_search(const Eigen::Vector3f& q,
                                                          float radius) const {
  std::vector<std::pair<float, std::uint32_t>> hits;
  for (std::size_t i = 0; i < points_.size(); ++i) {
    const float d2 = (points_[i] - q).squaredNorm();
    if (d2 <= radius * radius) hits.emplace_back(d2, static_cast<std::uint32_t>(i));
  }
  std::sort(hits.begin(), hits.end());
  std::vector<std::uint32_t> out;
  out.reserve(hits.size());
  for (const auto& h : hits) out.push_back(h.second);
  return out;
}

}  // namespace meshflow
