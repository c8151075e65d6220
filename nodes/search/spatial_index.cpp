#include "nodes/search/spatial_index.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <utility>

#include "nodes/search/bucket_kd_tree.h"

namespace meshflow {

struct KdTreeIndex::Impl {
  const std::vector<Eigen::Vector3f>& points;  // the caller's (knn_rows() recognises them)
  kd_tree::BucketTree tree;
  explicit Impl(const std::vector<Eigen::Vector3f>& cloud) : points(cloud), tree(cloud) {}
};

KdTreeIndex::KdTreeIndex(const std::vector<Eigen::Vector3f>& points) : size_(points.size()) {
  if (points.size() >= std::numeric_limits<std::uint32_t>::max() - 8)
    throw std::length_error("KdTreeIndex: more than 2^32 - 9 points");
  if (points.empty()) return;
  impl_ = std::make_unique<Impl>(points);  // builds the tree
}

KdTreeIndex::~KdTreeIndex() = default;

std::size_t KdTreeIndex::knn(const Eigen::Vector3f& q, std::size_t k, std::uint32_t* indices,
                             float* squared_distances) const {
  if (size_ == 0) return 0;
  return impl_->tree.knn(q, k, indices, squared_distances);
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
  if (size_ == 0 || k == 0) {
    std::fill(counts, counts + queries.size(), 0u);
    return;
  }
  if (&queries == &impl_->points) {  // the indexed points themselves
    impl_->tree.knn_of_points(queries, k, k, indices, counts);
    return;
  }
  SpatialIndex::knn_rows(queries, k, indices, counts);
}

std::vector<std::uint32_t> KdTreeIndex::radius_search(const Eigen::Vector3f& q,
                                                      float radius) const {
  if (size_ == 0) return {};
  std::vector<std::pair<std::uint32_t, float>> hits;
  impl_->tree.radius(q, radius * radius, hits);
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
