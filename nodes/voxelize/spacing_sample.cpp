#include "nodes/voxelize/spacing_sample.h"

#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>
#include <unordered_map>

#include "nodes/io/byte_buffer.h"
#include "runtime/parallel.h"

namespace meshflow {
namespace {

constexpr double kPi = 3.14159265358979323846;

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
  offer_scouts(points);
  for (const Eigen::Vector3f& p : points)
    if (p.allFinite()) bounds_.extend(p);
}

void SpacingSample::measure(const std::vector<Eigen::Vector3f>& points, const SpatialIndex& index) {
  scouts_ = {};  // what measure(points) bounds the reach by: not needed here
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

void SpacingSample::offer_scouts(const std::vector<Eigen::Vector3f>& points) {
  // Every scout_stride_-th point offered (a uniform subsample of a file written in any order);
  // where that would pass 2 kSpacingScouts, every other one is dropped and the stride doubles.
  thin_scouts(points.size());
  std::size_t at = scout_skip_;
  for (; at < points.size(); at += scout_stride_)
    if (points[at].allFinite()) scouts_.push_back(points[at]);
  scout_skip_ = at - points.size();
}

void SpacingSample::thin_scouts(std::size_t coming) {
  while (scouts_.size() + (coming + scout_stride_ - 1) / scout_stride_ > 2 * kSpacingScouts) {
    for (std::size_t i = 0; 2 * i < scouts_.size(); ++i) scouts_[i] = scouts_[2 * i];
    scouts_.resize((scouts_.size() + 1) / 2);
    scout_stride_ *= 2;
    scout_skip_ = 0;
  }
}

void SpacingSample::measure(const std::vector<Eigen::Vector3f>& points) {
  if (points.empty()) return;
  const float unknown = std::numeric_limits<float>::infinity();
  if (scout_reach2_.size() != samples_.size()) {  // the first call: the scouts bound the reach
    scout_reach2_.assign(samples_.size(), unknown);
    if (scouts_.size() >= neighbours_) {
      const KdTreeIndex index(scouts_);
      tbb::parallel_for(std::size_t{0}, samples_.size(), [&](std::size_t s) {
        std::vector<std::uint32_t> idx(neighbours_);
        std::vector<float> d2(neighbours_);
        if (index.knn(samples_[s].position, neighbours_, idx.data(), d2.data()) == neighbours_)
          scout_reach2_[s] = d2[neighbours_ - 1];
      });
    }
    scouts_ = {};
  }
  std::vector<float> reach2(samples_.size());
  bool bounded = true;
  for (std::size_t s = 0; s < samples_.size(); ++s) {
    const auto& nearest = samples_[s].nearest;
    reach2[s] =
        std::min(scout_reach2_[s], nearest.size() >= neighbours_ ? nearest.back().first : unknown);
    bounded = bounded && reach2[s] < unknown;
  }
  if (bounded) return measure_within_reach(points, reach2);
  const KdTreeIndex index(points);  // fewer points than neighbours offered: no reach yet
  measure(points, index);
}

namespace {

// A cell of a grid, hashed (two cells may share a key: their samples are then both checked,
// by exact distance, so a collision costs time only).
std::uint64_t reach_cell_key(std::int64_t x, std::int64_t y, std::int64_t z) {
  return static_cast<std::uint64_t>(x) * 0x9e3779b97f4a7c15ULL ^
         static_cast<std::uint64_t>(y) * 0xc2b2ae3d27d4eb4fULL ^
         static_cast<std::uint64_t>(z) * 0x165667b19e3779f9ULL;
}

// The cell holding coordinate `x` on a grid of cells 1 / `inverse` metres: float arithmetic
// (cheap per point), monotonic in x (a product and floor are), so a point within a ball lies
// in a cell between those of the ball's box's ends.
std::int64_t reach_cell(float x, float inverse) {
  return static_cast<std::int64_t>(std::floor(x * inverse));
}

// Squared distance as the kd-tree's leaf scan computes it (bucket_distance2(): the same
// rounding, so a neighbour found either way has the same distance).
float reach_distance2(const Eigen::Vector3f& query, const Eigen::Vector3f& p) {
  const float dx = p[0] - query[0], dy = p[1] - query[1], dz = p[2] - query[2];
  float d = dx * dx;
  d += dy * dy;
  d += dz * dz;
  return d;
}

// The samples whose reach (a ball) touches each cell of one grid, and a bit per hashed cell
// that says whether any does (most points are near no sample: one bit test each).
struct ReachGrid {
  double cell = 0.0;
  float inverse = 0.0f;  // 1 / cell
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> samples;
  std::vector<std::uint64_t> bits;  // kReachBits bits
};
constexpr int kReachShift = 64 - 18;  // a key's top 18 bits: its bit
constexpr std::size_t kReachBits = std::size_t{1} << (64 - kReachShift);
constexpr int kReachLevels = 24;  // cells of h0, 4 h0, 16 h0, ...

}  // namespace

void SpacingSample::measure_within_reach(const std::vector<Eigen::Vector3f>& points,
                                         const std::vector<float>& reach2) {
  // Only samples whose reach touches the batch's box can gain a neighbour from it.
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3f& p : points)
    if (p.allFinite()) box.extend(p.cast<double>());
  if (box.isEmpty()) return;
  std::vector<double> reach(samples_.size());
  std::vector<std::uint8_t> near_box(samples_.size(), 0);
  std::vector<double> positive;
  for (std::size_t s = 0; s < samples_.size(); ++s) {
    reach[s] = std::sqrt(static_cast<double>(reach2[s])) * (1.0 + 1e-6);
    near_box[s] = box.exteriorDistance(samples_[s].position.cast<double>()) <= reach[s] ? 1 : 0;
    if (near_box[s] && reach[s] > 0.0) positive.push_back(reach[s]);
  }
  double base = 1.0;  // the first level's cell: twice the 10th percentile of the reaches
  if (!positive.empty()) {
    const std::size_t tenth = positive.size() / 10;
    std::nth_element(positive.begin(), positive.begin() + static_cast<std::ptrdiff_t>(tenth),
                     positive.end());
    base = 2.0 * positive[tenth];
  }
  // Each sample on the first level whose cells are at least twice its reach (<= 8 cells).
  std::vector<ReachGrid> levels(kReachLevels);
  for (int l = 0; l < kReachLevels; ++l) {
    levels[l].cell = base * std::pow(4.0, l);
    levels[l].inverse = static_cast<float>(1.0 / levels[l].cell);
  }
  for (std::size_t s = 0; s < samples_.size(); ++s) {
    if (!near_box[s]) continue;
    int l = 0;
    while (l + 1 < kReachLevels && 2.0 * reach[s] > levels[l].cell) ++l;
    ReachGrid& grid = levels[l];
    const Eigen::Vector3d c = samples_[s].position.cast<double>();
    std::int64_t lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {  // the cells of the ball's box, its ends rounded outwards
      const float low = std::nextafter(static_cast<float>(c[k] - reach[s]), -HUGE_VALF);
      const float high = std::nextafter(static_cast<float>(c[k] + reach[s]), HUGE_VALF);
      lo[k] = reach_cell(low, grid.inverse);
      hi[k] = reach_cell(high, grid.inverse);
    }
    if (grid.bits.empty()) grid.bits.assign(kReachBits / 64, 0);
    for (std::int64_t x = lo[0]; x <= hi[0]; ++x)
      for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
        for (std::int64_t z = lo[2]; z <= hi[2]; ++z) {
          const std::uint64_t key = reach_cell_key(x, y, z);
          grid.samples[key].push_back(static_cast<std::uint32_t>(s));
          const std::uint64_t bit = key >> kReachShift;
          grid.bits[bit / 64] |= std::uint64_t{1} << (bit % 64);
        }
  }
  std::vector<const ReachGrid*> used;
  for (const ReachGrid& g : levels)
    if (!g.samples.empty()) used.push_back(&g);
  if (used.empty()) return;  // the batch is beyond every sample's reach
  // Candidates per fixed block of points, joined in block order (the lists are sorted by the
  // total order anyway).
  struct Candidate {
    std::uint32_t sample;
    float d2;
    Eigen::Vector3f point;
  };
  const std::size_t n = points.size();
  const std::size_t blocks = (n + kParallelBlock - 1) / kParallelBlock;
  std::vector<std::vector<Candidate>> found(blocks);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    const std::size_t end = std::min(n, (b + 1) * kParallelBlock);
    for (std::size_t i = b * kParallelBlock; i < end; ++i) {
      const Eigen::Vector3f& p = points[i];
      if (!p.allFinite()) continue;
      for (const ReachGrid* g : used) {
        const std::uint64_t key =
            reach_cell_key(reach_cell(p[0], g->inverse), reach_cell(p[1], g->inverse),
                           reach_cell(p[2], g->inverse));
        const std::uint64_t bit = key >> kReachShift;
        if (!((g->bits[bit / 64] >> (bit % 64)) & 1)) continue;
        const auto hit = g->samples.find(key);
        if (hit == g->samples.end()) continue;
        for (const std::uint32_t s : hit->second) {
          const float d2 = reach_distance2(samples_[s].position, p);
          if (d2 <= reach2[s]) found[b].push_back({s, d2, p});
        }
      }
    }
  });
  std::vector<std::uint8_t> touched(samples_.size(), 0);
  for (const std::vector<Candidate>& block : found)
    for (const Candidate& c : block) {
      samples_[c.sample].nearest.emplace_back(c.d2, c.point);
      touched[c.sample] = 1;
    }
  tbb::parallel_for(std::size_t{0}, samples_.size(), [&](std::size_t s) {
    if (touched[s]) keep_nearest(samples_[s].nearest);
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
  scouts_.insert(scouts_.end(), other.scouts_.begin(), other.scouts_.end());
  scout_stride_ = std::max(scout_stride_, other.scout_stride_);
  thin_scouts(0);
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
  w.u64(scouts_.size());
  for (const Eigen::Vector3f& p : scouts_)
    for (int k = 0; k < 3; ++k) w.f32(p[k]);
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
  const std::uint64_t scouts = r.u64("scouts");
  if (scouts > 2 * kSpacingScouts) r.fail("scouts", "more than 2 kSpacingScouts");
  for (std::uint64_t i = 0; i < scouts; ++i) sample.scouts_.push_back(point("scout"));
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

float SpacingSample::surface_density() const {
  std::vector<double> density;
  for (const Sample& s : samples_) {
    if (s.nearest.size() < 3 || !(s.nearest.back().first > 0.0f)) continue;
    const double others = static_cast<double>(s.nearest.size() - 1);
    density.push_back(others / (kPi * static_cast<double>(s.nearest.back().first)));
  }
  if (density.empty()) return 0.0f;
  const std::size_t middle = density.size() / 2;
  std::nth_element(density.begin(), density.begin() + static_cast<std::ptrdiff_t>(middle),
                   density.end());
  return static_cast<float>(density[middle]);
}

float auto_voxel_size(const PointCloud& cloud, const SpatialIndex& index, float factor) {
  SpacingSample sample;
  sample.offer(cloud.positions);
  sample.measure(cloud.positions, index);
  return sample.voxel_size(factor);
}

}  // namespace meshflow
