#include "nodes/search/spatial_index.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <Eigen/Geometry>
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
  bool addPoint(float dist, std::uint32_t local) {  // NOLINT(readability-identifier-naming)
    const std::uint32_t idx = ids_[local];
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
  // The indices in the whole set of the points of the part searched next.
  void search_part(const std::uint32_t* ids) { ids_ = ids; }

 private:
  const std::uint32_t* ids_ = nullptr;
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
  bool addPoint(float dist, std::uint32_t local) {  // NOLINT(readability-identifier-naming)
    if (dist <= squared_radius_) hits_.emplace_back(ids_[local], dist);
    return true;
  }
  bool full() const { return true; }
  // As KnnResult::search_part().
  void search_part(const std::uint32_t* ids) { ids_ = ids; }

 private:
  const std::uint32_t* ids_ = nullptr;
  float squared_radius_;
  float bound_;
  std::vector<std::pair<std::uint32_t, float>>& hits_;
};

}  // namespace

namespace kd_tree {

// One tree over a part of the points, copied contiguously (the tree reads them without an
// indirection), with each one's index in the whole set and the part's bounding box.
struct Part {
  std::vector<Eigen::Vector3f> points;
  std::vector<std::uint32_t> ids;
  Eigen::AlignedBox3f box;
  PackedPoints adaptor;
  std::unique_ptr<Tree> tree;

  Part(const std::vector<Eigen::Vector3f>& all, std::vector<std::uint32_t> part_ids)
      : ids(std::move(part_ids)) {
    points.reserve(ids.size());
    for (const std::uint32_t i : ids) {
      points.push_back(all[i]);
      box.extend(all[i]);
    }
    adaptor = PackedPoints{points.data(), points.size()};
    tree = std::make_unique<Tree>(3, adaptor,
                                  nanoflann::KDTreeSingleIndexAdaptorParams(/*leaf_max_size=*/10));
  }

  // Squared distance from q to the box (0 inside).
  float box_distance2(const Eigen::Vector3f& q) const {
    return (box.min() - q).cwiseMax(q - box.max()).cwiseMax(0.0f).squaredNorm();
  }

  // Runs `result` over this part's tree unless the box lies beyond its bound.
  template <class Result>
  void search(Result& result, const Eigen::Vector3f& q) const {
    // 1e-5 below: a point on the box's surface, whose distance nanoflann rounds in its own
    // order, is never left out.
    if (!(box_distance2(q) * (1.0f - 1e-5f) < result.worstDist())) return;
    result.search_part(ids.data());
    tree->findNeighbors(result, q.data(), nanoflann::SearchParams(0, 0.0f, false));
  }
};

}  // namespace kd_tree

// Two trees over the points either side of the median of the bounding box's longest axis,
// built at once on two threads (nanoflann builds a tree serially: 9 ms of kurt3d scan000's
// normals, a fifth, ran on one core). A query searches its own half first, then the other one
// only when that half's box lies nearer than its k-th neighbour so far. Small sets: one tree.
struct KdTreeIndex::Impl {
  const Eigen::Vector3f* points;                      // the caller's points
  std::vector<std::unique_ptr<kd_tree::Part>> parts;  // (the trees refer to their part)

  explicit Impl(const std::vector<Eigen::Vector3f>& cloud) : points(cloud.data()) { build(cloud); }

  void build(const std::vector<Eigen::Vector3f>& cloud) {
    const auto n = static_cast<std::uint32_t>(cloud.size());
    std::vector<std::uint32_t> low, high;
    if (n >= kMinSplit) {
      Eigen::AlignedBox3f box;
      for (const Eigen::Vector3f& p : cloud) box.extend(p);
      Eigen::Index axis = 0;
      box.sizes().maxCoeff(&axis);
      std::vector<float> c(n);
      for (std::uint32_t i = 0; i < n; ++i) c[i] = cloud[i][axis];
      const auto middle = c.begin() + n / 2;
      std::nth_element(c.begin(), middle, c.end());
      const float split = *middle;
      low.reserve(n / 2 + 1);
      high.reserve(n / 2 + 1);
      for (std::uint32_t i = 0; i < n; ++i) (cloud[i][axis] < split ? low : high).push_back(i);
    }
    if (low.empty() || high.empty()) {  // small, or too many points on the median plane
      std::vector<std::uint32_t> ids(n);
      for (std::uint32_t i = 0; i < n; ++i) ids[i] = i;
      parts.push_back(std::make_unique<kd_tree::Part>(cloud, std::move(ids)));
      return;
    }
    parts.resize(2);
    tbb::parallel_invoke(
        [&] { parts[0] = std::make_unique<kd_tree::Part>(cloud, std::move(low)); },
        [&] { parts[1] = std::make_unique<kd_tree::Part>(cloud, std::move(high)); });
  }

  // The trees' leaf order (points of a leaf, then of its sibling, ...) as indices of the set.
  std::vector<std::uint32_t> leaf_order() const {
    std::vector<std::uint32_t> order;
    for (const auto& part : parts)
      for (const std::uint32_t local : part->tree->vAcc) order.push_back(part->ids[local]);
    return order;
  }

  // Searches the part whose box is nearest q first, then the other.
  template <class Result>
  void search(Result& result, const Eigen::Vector3f& q) const {
    if (parts.size() == 1) {
      parts[0]->search(result, q);
      return;
    }
    const bool second_first = parts[1]->box_distance2(q) < parts[0]->box_distance2(q);
    parts[second_first ? 1 : 0]->search(result, q);
    parts[second_first ? 0 : 1]->search(result, q);
  }

  static constexpr std::uint32_t kMinSplit = 16384;
};

KdTreeIndex::KdTreeIndex(const std::vector<Eigen::Vector3f>& points) : size_(points.size()) {
  if (points.size() >= std::numeric_limits<std::uint32_t>::max())
    throw std::length_error("KdTreeIndex: more than 2^32 - 1 points");
  if (points.empty()) return;
  impl_ = std::make_unique<Impl>(points);  // builds the trees
}

KdTreeIndex::~KdTreeIndex() = default;

std::size_t KdTreeIndex::knn(const Eigen::Vector3f& q, std::size_t k, std::uint32_t* indices,
                             float* squared_distances) const {
  k = std::min(k, size_);
  if (k == 0) return 0;
  KnnResult result(k, indices, squared_distances);
  impl_->search(result, q);
  return result.size();
}

void SpatialIndex::knn_rows(const std::vector<Eigen::Vector3f>& queries, std::size_t k,
                            std::uint32_t* indices, std::uint32_t* counts) const {
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, queries.size(), 512),
      [&](const tbb::blocked_range<std::size_t>& r) {
        std::vector<float> d2(k);
        for (std::size_t i = r.begin(); i != r.end(); ++i)
          counts[i] = static_cast<std::uint32_t>(knn(queries[i], k, indices + i * k, d2.data()));
      });
}

void KdTreeIndex::knn_rows(const std::vector<Eigen::Vector3f>& queries, std::size_t k,
                           std::uint32_t* indices, std::uint32_t* counts) const {
  const std::size_t m = queries.size();
  const std::size_t stride = k;  // the caller's row width
  k = std::min(k, size_);
  if (k == 0) {
    std::fill(counts, counts + m, 0u);
    return;
  }
  // The indexed points themselves are taken in the trees' leaf order.
  const std::vector<std::uint32_t> order = queries.data() == impl_->points && m == size_
                                               ? impl_->leaf_order()
                                               : std::vector<std::uint32_t>();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 512),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      std::vector<float> d2(k);
                      for (std::size_t j = r.begin(); j != r.end(); ++j) {
                        const std::size_t i = order.empty() ? j : order[j];
                        KnnResult result(k, indices + i * stride, d2.data());
                        impl_->search(result, queries[i]);
                        counts[i] = static_cast<std::uint32_t>(result.size());
                      }
                    });
}

std::vector<std::uint32_t> KdTreeIndex::radius_search(const Eigen::Vector3f& q,
                                                      float radius) const {
  if (size_ == 0) return {};
  std::vector<std::pair<std::uint32_t, float>> hits;
  RadiusResult result(radius * radius, hits);
  impl_->search(result, q);
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
