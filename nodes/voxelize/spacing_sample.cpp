#include "nodes/voxelize/spacing_sample.h"

#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>

#include "nodes/io/byte_buffer.h"
#include "runtime/parallel.h"

namespace meshflow {
namespace {

std::uint64_t spacing_mix(std::uint64_t x) {  // splitmix64's finaliser
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Total order of points by their coordinates' bits: the tie-break of equal ranks and distances.
bool spacing_bits_less(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  for (int k = 0; k < 3; ++k) {
    std::uint32_t x, y;
    std::memcpy(&x, &a[k], 4);
    std::memcpy(&y, &b[k], 4);
    if (x != y) return x < y;
  }
  return false;
}

// Plane-fit variation of a neighbourhood (smallest covariance eigenvalue over their sum).
float spacing_variation(const std::vector<std::pair<float, Eigen::Vector3f>>& points) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p.second.cast<double>();
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : points) {
    const Eigen::Vector3d d = p.second.cast<double>() - mean;
    cov += d * d.transpose();
  }
  const Eigen::Vector3d values = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvalues();
  const double total = values.sum();
  return total > 0.0 ? static_cast<float>(std::max(0.0, values[0]) / total) : 1.0f;
}

}  // namespace

std::uint64_t spacing_sample_rank(const Eigen::Vector3f& p) {
  // The coordinates on a 1/1024 m lattice, not their bits: two readers of one file that differ
  // in the last bit (a georeferenced file read in a local frame, or near the world origin)
  // rank its points alike (equal ranks are ordered by the points' bits).
  std::uint64_t q[3];
  for (int k = 0; k < 3; ++k)
    q[k] = static_cast<std::uint64_t>(std::llround(static_cast<double>(p[k]) * 1024.0));
  return spacing_mix(spacing_mix(spacing_mix(q[0]) ^ q[1]) ^ q[2]);
}

SpacingSample::SpacingSample(std::size_t neighbours)
    : neighbours_(std::max<std::size_t>(2, neighbours)) {}

void SpacingSample::offer(const std::vector<Eigen::Vector3f>& points) {
  const std::size_t n = points.size();
  if (n == 0) return;
  // Candidates: points ranked below a threshold expected to pass a few times the samples (ranks
  // are uniform), raised until enough pass; the lowest-ranked of the batch are all among them.
  std::vector<std::uint32_t> candidates;
  const double wanted = 4.0 * static_cast<double>(kSpacingSamples) / static_cast<double>(n);
  double fraction = std::min(1.0, wanted);
  for (;;) {
    const std::uint64_t limit = fraction >= 1.0
                                    ? std::numeric_limits<std::uint64_t>::max()
                                    : static_cast<std::uint64_t>(fraction * 18446744073709551615.0);
    candidates = parallel_select_indices(n, [&](std::size_t i) {
      return points[i].allFinite() && spacing_sample_rank(points[i]) <= limit;
    });
    if (candidates.size() >= kSpacingSamples || fraction >= 1.0) break;
    fraction = std::min(1.0, fraction * 16.0);
  }
  for (const std::uint32_t i : candidates)
    samples_.push_back({spacing_sample_rank(points[i]), points[i], {}});
  keep_lowest();
  for (const Eigen::Vector3f& p : points)
    if (p.allFinite()) bounds_.extend(p);
}

void SpacingSample::measure(const std::vector<Eigen::Vector3f>& points, const SpatialIndex& index) {
  if (points.empty()) return;
  const std::size_t k = std::min(neighbours_, index.size());
  tbb::parallel_for(std::size_t{0}, samples_.size(), [&](std::size_t s) {
    std::vector<std::uint32_t> idx(k);
    std::vector<float> d2(k);
    const std::size_t found = index.knn(samples_[s].position, k, idx.data(), d2.data());
    auto& nearest = samples_[s].nearest;
    for (std::size_t j = 0; j < found; ++j) nearest.emplace_back(d2[j], points[idx[j]]);
    keep_nearest(nearest);
  });
}

void SpacingSample::keep_lowest() {
  const auto less = [](const Sample& a, const Sample& b) {
    return a.rank != b.rank ? a.rank < b.rank : spacing_bits_less(a.position, b.position);
  };
  if (samples_.size() > kSpacingSamples) {
    std::nth_element(samples_.begin(),
                     samples_.begin() + static_cast<std::ptrdiff_t>(kSpacingSamples),
                     samples_.end(), less);
    samples_.resize(kSpacingSamples);
  }
  std::sort(samples_.begin(), samples_.end(), less);
}

void SpacingSample::keep_nearest(std::vector<std::pair<float, Eigen::Vector3f>>& nearest) const {
  std::sort(nearest.begin(), nearest.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first < b.first : spacing_bits_less(a.second, b.second);
  });
  if (nearest.size() > neighbours_) nearest.resize(neighbours_);
}

void SpacingSample::merge_offered(const SpacingSample& other) {
  samples_.insert(samples_.end(), other.samples_.begin(), other.samples_.end());
  keep_lowest();
  bounds_.extend(other.bounds_);
}

void SpacingSample::merge_measured(const SpacingSample& other) {
  assert(other.samples_.size() == samples_.size());
  for (std::size_t s = 0; s < samples_.size(); ++s) {
    auto& nearest = samples_[s].nearest;
    const auto& more = other.samples_[s].nearest;
    nearest.insert(nearest.end(), more.begin(), more.end());
    keep_nearest(nearest);
  }
}

std::vector<unsigned char> SpacingSample::to_bytes() const {
  io::ByteWriter w;
  w.u64(neighbours_);
  for (int k = 0; k < 3; ++k) w.f32(bounds_.min()[k]);
  for (int k = 0; k < 3; ++k) w.f32(bounds_.max()[k]);
  w.u64(samples_.size());
  for (const Sample& s : samples_) {
    w.u64(s.rank);
    for (int k = 0; k < 3; ++k) w.f32(s.position[k]);
    w.u64(s.nearest.size());
    for (const auto& [d2, p] : s.nearest) {
      w.f32(d2);
      for (int k = 0; k < 3; ++k) w.f32(p[k]);
    }
  }
  return std::move(w.out);
}

SpacingSample SpacingSample::from_bytes(const std::vector<unsigned char>& bytes,
                                        const std::string& source) {
  io::ByteReader r(source, bytes);
  const std::uint64_t neighbours = r.u64("neighbours");
  if (neighbours < 2 || neighbours > 1024) r.fail("neighbours", "expected 2 to 1024");
  SpacingSample sample(static_cast<std::size_t>(neighbours));
  const auto point = [&](const char* field) {
    Eigen::Vector3f p;
    for (int k = 0; k < 3; ++k) p[k] = r.f32(field);
    return p;
  };
  sample.bounds_.min() = point("bounds");
  sample.bounds_.max() = point("bounds");
  const std::uint64_t count = r.u64("samples");
  if (count > kSpacingSamples) r.fail("samples", "more than kSpacingSamples");
  for (std::uint64_t i = 0; i < count; ++i) {
    Sample s;
    s.rank = r.u64("rank");
    s.position = point("sample");
    const std::uint64_t near = r.u64("neighbour count");
    if (near > neighbours) r.fail("neighbour count", "more than the neighbours kept");
    for (std::uint64_t j = 0; j < near; ++j) {
      const float d2 = r.f32("distance");
      s.nearest.emplace_back(d2, point("neighbour"));
    }
    sample.samples_.push_back(std::move(s));
  }
  return sample;
}

float SpacingSample::voxel_size(float factor) const {
  std::vector<float> spacing;
  for (const Sample& s : samples_)
    if (s.nearest.size() >= 2) spacing.push_back(std::sqrt(s.nearest[1].first));
  if (spacing.empty()) return 0.05f;
  const std::size_t middle = spacing.size() / 2;
  std::nth_element(spacing.begin(), spacing.begin() + static_cast<std::ptrdiff_t>(middle),
                   spacing.end());
  const float diagonal = bounds_.isEmpty() ? 0.0f : bounds_.diagonal().norm();
  return std::max(factor * spacing[middle], diagonal / 2000.0f);
}

float SpacingSample::median_variation() const {
  std::vector<float> variation;
  for (const Sample& s : samples_)
    if (s.nearest.size() >= 3) variation.push_back(spacing_variation(s.nearest));
  if (variation.empty()) return 1.0f;
  const std::size_t middle = variation.size() / 2;
  std::nth_element(variation.begin(), variation.begin() + static_cast<std::ptrdiff_t>(middle),
                   variation.end());
  return variation[middle];
}

float auto_voxel_size(const PointCloud& cloud, const SpatialIndex& index, float factor) {
  SpacingSample sample;
  sample.offer(cloud.positions);
  sample.measure(cloud.positions, index);
  return sample.voxel_size(factor);
}

}  // namespace meshflow
