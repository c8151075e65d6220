#include "nodes/normals/spatial_index.h"

#include <flann/flann.hpp>

#include <algorithm>
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

std::size_t KdTreeIndex::knn(const Eigen::Vector3f& q, std::size_t k, std::uint32_t* indices,
                             float* squared_distances) const {
  k = std::min(k, size_);
  if (k == 0) return 0;
  flann::KNNSimpleResultSet<float> result(k);
  impl_->tree.findNeighbors(result, q.data(), flann::SearchParams(flann::FLANN_CHECKS_UNLIMITED, 0.0f, true));
  std::size_t idx[64];
  float d2[64];
  std::vector<std::size_t> idx_big;
  std::vector<float> d2_big;
  std::size_t* ip = idx;
  float* dp = d2;
  if (k > 64) {
    idx_big.resize(k);
    d2_big.resize(k);
    ip = idx_big.data();
    dp = d2_big.data();
  }
  result.copy(ip, dp, k, true);
  const std::size_t found = std::min(k, result.size());
  for (std::size_t i = 0; i < found; ++i) {
    indices[i] = static_cast<std::uint32_t>(ip[i]);
    squared_distances[i] = dp[i];
  }
  return found;
}

std::vector<std::uint32_t> KdTreeIndex::radius_search(const Eigen::Vector3f& q, float radius) const {
  if (size_ == 0) return {};
  flann::RadiusResultSet<float> result(radius * radius);
  impl_->tree.findNeighbors(result, q.data(), flann::SearchParams(flann::FLANN_CHECKS_UNLIMITED, 0.0f, true));
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

std::vector<std::uint32_t> BruteForceIndex::radius_search(const Eigen::Vector3f& q, float radius) const {
  std::vector<std::pair<float, std::uint32_t>> hits;
  for (std::size_t i = 0; i < points_.size(); ++i) {
    const float d2 = (points_[i] - q).squaredNorm();
    if (d2 <= radius * radius) hits.emplace_back(d2, static_cast<std::uint32_t>(i));
  }
  std::sort(hits.begin(), hits.end());
  std::vector<std::uint32_t> out;
  for (const auto& h : hits) out.push_back(h.second);
  return out;
}

}  // namespace meshflow
