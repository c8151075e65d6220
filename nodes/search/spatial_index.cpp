#include "nodes/search/spatial_index.h"

#include <flann/flann.hpp>

#include <algorithm>
#include <limits>
#include <numeric>

namespace meshflow {

struct KdTreeIndex::Impl {
  flann::KDTreeSingleIndex<flann::L2_Simple<float>> tree;
  explicit Impl(const flann::Matrix<float>& data)
      : tree(data, flann::KDTreeSingleIndexParams(/*leaf_max_size=*/10, /*reorder=*/true)) {}
};

KdTreeIndex::KdTreeIndex(const std::vector<Eigen::Vector3f>& points) : size_(points.size()) {
  if (points.empty()) return;
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "points must be packed xyz");
  // FLANN takes a non-const pointer but only reads it (the tree reorders its own copy).
  const flann::Matrix<float> data(const_cast<float*>(points.front().data()), points.size(), 3);
  impl_ = std::make_unique<Impl>(data);
  impl_->tree.buildIndex();
}

KdTreeIndex::~KdTreeIndex() = default;

namespace {

// k-nearest result set writing straight into the caller's arrays: no heap allocation per
// query (FLANN's own result sets allocate), ties broken by the smaller index.
class CallerKnnResult final : public flann::ResultSet<float> {
 public:
  CallerKnnResult(std::size_t k, std::uint32_t* indices, float* dists)
      : k_(k), indices_(indices), dists_(dists) {}
  bool full() const override { return count_ == k_; }
  float worstDist() const override {
    return count_ == k_ ? dists_[k_ - 1] : std::numeric_limits<float>::max();
  }
  void addPoint(float dist, std::size_t index) override {
    const auto idx = static_cast<std::uint32_t>(index);
    if (count_ == k_ &&
        !(dist < dists_[k_ - 1] || (dist == dists_[k_ - 1] && idx < indices_[k_ - 1]))) {
      return;
    }
    std::size_t i = count_ < k_ ? count_++ : k_ - 1;
    for (; i > 0 && (dists_[i - 1] > dist || (dists_[i - 1] == dist && indices_[i - 1] > idx));
         --i) {
      dists_[i] = dists_[i - 1];
      indices_[i] = indices_[i - 1];
    }
    dists_[i] = dist;
    indices_[i] = idx;
  }
  std::size_t size() const { return count_; }

 private:
  std::size_t k_;
  std::uint32_t* indices_;
  float* dists_;
  std::size_t count_ = 0;
};

}  // namespace

std::size_t KdTreeIndex::knn(const Eigen::Vector3f& q, std::size_t k, std::uint32_t* indices,
                             float* squared_distances) const {
  k = std::min(k, size_);
  if (k == 0) return 0;
  CallerKnnResult result(k, indices, squared_distances);
  impl_->tree.findNeighbors(result, q.data(),
                            flann::SearchParams(flann::FLANN_CHECKS_UNLIMITED, 0.0f, false));
  return result.size();
}

std::vector<std::uint32_t> KdTreeIndex::radius_search(const Eigen::Vector3f& q,
                                                      float radius) const {
  if (size_ == 0) return {};
  flann::RadiusResultSet<float> result(radius * radius);
  impl_->tree.findNeighbors(result, q.data(),
                            flann::SearchParams(flann::FLANN_CHECKS_UNLIMITED, 0.0f, true));
  const std::size_t n = result.size();
  std::vector<std::size_t> idx(n);
  std::vector<float> d2(n);
  if (n > 0) result.copy(idx.data(), d2.data(), n, true);
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return d2[a] < d2[b] || (d2[a] == d2[b] && idx[a] < idx[b]);
  });
  std::vector<std::uint32_t> out(n);
  for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<std::uint32_t>(idx[order[i]]);
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
