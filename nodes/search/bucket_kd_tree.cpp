#include "nodes/search/bucket_kd_tree.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "runtime/simd.h"

namespace meshflow::kd_tree {

struct BucketTree::Item {
  float p[3];
  std::uint32_t id;
};

namespace {

using simd::Floats8;
using Floats4 = float __attribute__((vector_size(16)));  // x, y, z, 0

// Subtrees of at least this many points are built in parallel.
constexpr std::uint32_t kBucketParallelBuild = 4096;

// What a search reads: the tree's arrays.
struct BucketView {
  const BucketTree::Node* nodes;
  const float* xs;
  const float* ys;
  const float* zs;
  const std::uint32_t* ids;
};

// The squared length of the per-axis gaps max(below, above, 0), summed x + y, then + z (the
// order every caller's bound relies on).
inline float bucket_gap_distance2(const Floats4& below, const Floats4& above) {
  Floats4 d = below > above ? below : above;
  d = d > 0.0f ? d : Floats4{};
  d *= d;
  float s = d[0] + d[1];
  s += d[2];
  return s;
}

// Squared distance from q to the node's box (0 inside). Rounding is monotone, so for every point
// p of the box each axis term is at most p's and the sum, taken in the same order as a point's,
// never exceeds p's computed squared distance: a box is skipped only when all of its points lie
// beyond the bound.
inline float bucket_box_distance2(const BucketTree::Node& n, const Floats4& q) {
  Floats4 lo, hi;
  std::memcpy(&lo, n.lo, sizeof lo);
  std::memcpy(&hi, n.hi, sizeof hi);
  return bucket_gap_distance2(lo - q, q - hi);
}

// Scratch slots a k-best list (BucketKnn) takes: a sentinel, then k rounded up to whole vectors.
constexpr std::size_t bucket_knn_slots(std::size_t k) { return 1 + ((k + 3) & ~std::size_t{3}); }

// The k smallest (squared distance, index) pairs, ties by the smaller index, so the result is
// the brute-force one. Each pair is kept as one 64-bit key, the distance's bits above the index:
// non-negative floats order as their bits, so one integer comparison orders pairs by distance,
// then index. The keys are kept sorted; a closer point is inserted without branches, four keys
// at a time: slot i becomes min(key[i], max(key[i - 1], new)). `slots` is the caller's scratch
// of bucket_knn_slots(k) entries. kGroups: the number of four-key groups when the caller knows
// it at compile time ((k + 3) / 4: the insertion unrolled), 0 otherwise.
template <int kGroups = 0>
class BucketKnn {
 public:
  // Only points within squared distance `cap` (inclusive) are taken: for a search known to have
  // at least k points there the result is unchanged, and the tree is pruned from the start.
  BucketKnn(std::size_t k, std::uint64_t* slots, float cap = std::numeric_limits<float>::infinity())
      : k_(k), keys_(slots + 1), worst_(cap) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &cap, sizeof bits);
    slots[0] = 0;  // below every key
    // Empty slots: at the cap, after every index.
    worst_key_ = std::uint64_t{bits} << 32 | 0xffffffffu;
    std::fill(keys_, keys_ + ((k + 3) & ~std::size_t{3}), worst_key_);
  }
  // Candidates farther than this cannot enter (equal ones can, with a smaller index).
  float worst() const { return worst_; }
  void add(float dist, std::uint32_t idx) {
    using Keys4 = std::int64_t __attribute__((vector_size(32)));  // keys are below 2^63
    std::uint32_t bits = 0;
    std::memcpy(&bits, &dist, sizeof bits);
    const std::uint64_t key = static_cast<std::uint64_t>(bits) << 32 | idx;
    if (key >= worst_key_) return;
    const Keys4 in = Keys4{} + static_cast<std::int64_t>(key);
    const int groups = kGroups != 0 ? kGroups : static_cast<int>((k_ + 3) / 4);
    for (int g = groups - 1; g >= 0; --g) {  // from the top: each reads the group below unchanged
      const auto i = static_cast<std::size_t>(4 * g);
      // The group below read whole, where the last insertion stored it (a load spanning two
      // stores is not forwarded), its top key shifted in by a lane shuffle.
      Keys4 at, lower{};
      std::memcpy(&at, keys_ + i, sizeof at);
      if (g > 0) std::memcpy(&lower, keys_ + i - 4, sizeof lower);
      Keys4 below = __builtin_shufflevector(lower, at, 3, 4, 5, 6);
      below = below > in ? below : in;
      at = at < below ? at : below;
      std::memcpy(keys_ + i, &at, sizeof at);
    }
    count_ += count_ < k_;
    worst_key_ = keys_[k_ - 1];
    const auto hi = static_cast<std::uint32_t>(worst_key_ >> 32);
    std::memcpy(&worst_, &hi, sizeof worst_);
  }
  std::size_t size() const { return count_; }
  // Writes the pairs found, closest first (`dists` may be null); returns how many.
  std::size_t finish(std::uint32_t* indices, float* dists) const {
    for (std::size_t i = 0; i < count_; ++i) {
      indices[i] = static_cast<std::uint32_t>(keys_[i]);
      if (dists != nullptr) {
        const auto top = static_cast<std::uint32_t>(keys_[i] >> 32);
        std::memcpy(dists + i, &top, sizeof top);
      }
    }
    return count_;
  }

 private:
  std::size_t k_;
  std::uint64_t* keys_;
  std::uint64_t worst_key_;  // keys_[k_ - 1]
  float worst_;              // its distance
  std::size_t count_ = 0;
};

// BucketKnn<> for a k known at compile time, its keys held in vector values (registers) rather
// than in the caller's scratch: each group's lower neighbour comes from a lane shuffle of the
// groups as they were, not from an unaligned reload of the keys just stored (which the store
// buffer cannot forward). The same keys, the same result.
template <int kK>
class BucketKnnFixed {
 public:
  BucketKnnFixed(std::size_t /*k*/, std::uint64_t* /*slots*/,
                 float cap = std::numeric_limits<float>::infinity())
      : worst_(cap) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &cap, sizeof bits);
    worst_key_ = std::uint64_t{bits} << 32 | 0xffffffffu;
    for (Keys4& g : groups_) g = Keys4{} + static_cast<std::int64_t>(worst_key_);
  }
  float worst() const { return worst_; }
  void add(float dist, std::uint32_t idx) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &dist, sizeof bits);
    const std::uint64_t key = static_cast<std::uint64_t>(bits) << 32 | idx;
    if (key >= worst_key_) return;
    const Keys4 in = Keys4{} + static_cast<std::int64_t>(key);
    for (int g = kGroups - 1; g >= 0; --g) {  // from the top: each reads the group below unchanged
      const Keys4 lower = g > 0 ? groups_[g - 1] : Keys4{};
      Keys4 below = __builtin_shufflevector(lower, groups_[g], 3, 4, 5, 6);
      below = below > in ? below : in;
      groups_[g] = groups_[g] < below ? groups_[g] : below;
    }
    count_ += count_ < kK;
    worst_key_ = static_cast<std::uint64_t>(groups_[(kK - 1) / 4][(kK - 1) % 4]);
    const auto hi = static_cast<std::uint32_t>(worst_key_ >> 32);
    std::memcpy(&worst_, &hi, sizeof worst_);
  }
  std::size_t size() const { return count_; }
  std::size_t finish(std::uint32_t* indices, float* dists) const {
    for (std::size_t i = 0; i < count_; ++i) {
      const auto key = static_cast<std::uint64_t>(groups_[i / 4][i % 4]);
      indices[i] = static_cast<std::uint32_t>(key);
      if (dists != nullptr) {
        const auto top = static_cast<std::uint32_t>(key >> 32);
        std::memcpy(dists + i, &top, sizeof top);
      }
    }
    return count_;
  }

 private:
  using Keys4 = std::int64_t __attribute__((vector_size(32)));  // keys are below 2^63
  static constexpr int kGroups = (kK + 3) / 4;
  Keys4 groups_[kGroups];
  std::uint64_t worst_key_;
  float worst_;
  std::size_t count_ = 0;
};

// Every point within a fixed squared radius (inclusive).
class BucketRadius {
 public:
  BucketRadius(float squared_radius, std::vector<std::pair<std::uint32_t, float>>& hits)
      : squared_radius_(squared_radius), hits_(hits) {}
  float worst() const { return squared_radius_; }
  void add(float dist, std::uint32_t idx) { hits_.emplace_back(idx, dist); }

 private:
  float squared_radius_;
  std::vector<std::pair<std::uint32_t, float>>& hits_;
};

// Bit j set where lane j of `in` (all ones or zero per lane) is set: the lanes' bits ORed
// together by three halving shuffles (no movemask: the baseline clone has no AVX).
inline __attribute__((always_inline)) unsigned bucket_lane_bits(const simd::Ints8& in) {
  simd::Ints8 s = in & simd::Ints8{1, 2, 4, 8, 16, 32, 64, 128};
  s |= __builtin_shufflevector(s, s, 4, 5, 6, 7, 0, 1, 2, 3);
  s |= __builtin_shufflevector(s, s, 2, 3, 0, 1, 6, 7, 4, 5);
  s |= __builtin_shufflevector(s, s, 1, 0, 3, 2, 5, 4, 7, 6);
  return static_cast<unsigned>(s[0]);
}

// Offers the leaf's points to `sink`, 8 squared distances at a time: ((dx dx + dy dy) + dz dz),
// the brute-force oracle's order (no FMA: the AVX2 clones do not enable it). Only lanes within
// the bound when their block is computed are offered; the sink checks each against its bound
// as it stands then.
template <class Sink>
inline __attribute__((always_inline)) void bucket_scan_leaf(const BucketView& v,
                                                            const BucketTree::Node& leaf,
                                                            const float* q, Sink& sink) {
  const float* const xs = v.xs;
  const float* const ys = v.ys;
  const float* const zs = v.zs;
  const std::uint32_t* const ids = v.ids;
  const float qx = q[0], qy = q[1], qz = q[2];
  const std::uint32_t begin = leaf.begin, count = leaf.count;
  const simd::Ints8 lane = {0, 1, 2, 3, 4, 5, 6, 7};
  for (std::uint32_t b = 0; b < count; b += 8) {
    const std::uint32_t at = begin + b;
    Floats8 x, y, z;
    std::memcpy(&x, xs + at, sizeof x);
    std::memcpy(&y, ys + at, sizeof y);
    std::memcpy(&z, zs + at, sizeof z);
    const Floats8 dx = x - qx, dy = y - qy, dz = z - qz;
    Floats8 d = dx * dx;
    d += dy * dy;
    d += dz * dz;
    unsigned mask = bucket_lane_bits((d <= sink.worst()) & (lane < static_cast<int>(count - b)));
    for (; mask != 0; mask &= mask - 1) {
      const unsigned j = static_cast<unsigned>(__builtin_ctz(mask));
      sink.add(d[j], ids[at + j]);
    }
  }
}

// Depth-first search from the root, the nearer child first; a node is entered only while its
// box is within the sink's bound.
template <class Sink>
inline __attribute__((always_inline)) void bucket_search(const BucketView& v, const float* q,
                                                         Sink& sink, std::uint32_t root = 0) {
  struct Pending {
    std::uint32_t node;
    float distance;
  };
  Pending stack[64];  // one entry per level at most: the tree is balanced, < 2^32 points
  int top = 0;
  std::uint32_t node = root;
  const Floats4 q4 = {q[0], q[1], q[2], 0.0f};
  if (!(bucket_box_distance2(v.nodes[root], q4) <= sink.worst())) return;
  for (;;) {
    const BucketTree::Node& n = v.nodes[node];
    if (n.count == 0) {  // inner: both children exist
      const std::uint32_t left = 2 * node + 1;
      const float dl = bucket_box_distance2(v.nodes[left], q4);
      const float dr = bucket_box_distance2(v.nodes[left + 1], q4);
      const bool left_first = dl <= dr;
      const std::uint32_t near = left_first ? left : left + 1;
      const float dnear = left_first ? dl : dr, dfar = left_first ? dr : dl;
      if (dfar <= sink.worst()) stack[top++] = {left_first ? left + 1 : left, dfar};
      if (dnear <= sink.worst()) {
        node = near;
        continue;
      }
    } else {
      bucket_scan_leaf(v, n, q, sink);
    }
    for (;;) {
      if (top == 0) return;
      const Pending p = stack[--top];
      if (p.distance <= sink.worst()) {
        node = p.node;
        break;
      }
    }
  }
}

MESHFLOW_AVX2_CLONES std::size_t bucket_knn_one(const BucketView& v, const float* q, std::size_t k,
                                                std::uint32_t* indices, float* squared_distances) {
  std::uint64_t local[bucket_knn_slots(64)];
  std::vector<std::uint64_t> heap(k > 64 ? bucket_knn_slots(k) : 0);
  BucketKnn<> best(k, k > 64 ? heap.data() : local);
  bucket_search(v, q, best);
  return best.finish(indices, squared_distances);
}

// Squared distance between two boxes (0 when they overlap), per axis the gap max(lo_b - hi_a,
// lo_a - hi_b, 0) in the order of bucket_box_distance2(): for a point q inside box a, rounding
// being monotone, each gap is at most q's gap to b, so the result never exceeds
// bucket_box_distance2(b, q).
inline float bucket_boxes_distance2(const BucketTree::Node& a, const BucketTree::Node& b) {
  Floats4 alo, ahi, blo, bhi;
  std::memcpy(&alo, a.lo, sizeof alo);
  std::memcpy(&ahi, a.hi, sizeof ahi);
  std::memcpy(&blo, b.lo, sizeof blo);
  std::memcpy(&bhi, b.hi, sizeof bhi);
  return bucket_gap_distance2(blo - ahi, alo - bhi);
}

// What the searches of one block of leaves reuse: two k-best lists' keys, the leaves near the
// current leaf.
struct BucketRowScratch {
  std::vector<std::uint64_t> keys;
  std::vector<std::uint32_t> near;  // leaf nodes
  std::vector<float> lo[3], hi[3];  // their boxes, axis by axis
  std::vector<std::uint32_t> stack;
};

// The leaves other than `own` whose boxes lie within squared distance `bound` of own's box, with
// their boxes in s.lo / s.hi (padded to a multiple of 8), found climbing from `own`: the
// subtree of its sibling first, then those of its ancestors' siblings, so nearer ones come
// first.
void bucket_leaves_near(const BucketView& v, std::uint32_t own, float bound, BucketRowScratch& s) {
  const BucketTree::Node& box = v.nodes[own];
  s.near.clear();
  for (std::uint32_t up = own; up != 0; up = (up - 1) / 2) {
    s.stack.assign(1, up % 2 == 1 ? up + 1 : up - 1);
    while (!s.stack.empty()) {
      const std::uint32_t node = s.stack.back();
      s.stack.pop_back();
      if (!(bucket_boxes_distance2(box, v.nodes[node]) <= bound)) continue;
      if (v.nodes[node].count != 0) {
        s.near.push_back(node);
      } else {
        s.stack.push_back(2 * node + 2);
        s.stack.push_back(2 * node + 1);
      }
    }
  }
  const std::size_t padded = (s.near.size() + 7) & ~std::size_t{7};
  for (int a = 0; a < 3; ++a) {
    s.lo[a].resize(padded);
    s.hi[a].resize(padded);
  }
  for (std::size_t c = 0; c < padded; ++c) {
    const BucketTree::Node& n = v.nodes[c < s.near.size() ? s.near[c] : own];
    for (int a = 0; a < 3; ++a) {
      s.lo[a][c] = n.lo[a];
      s.hi[a][c] = n.hi[a];
    }
  }
}

// Scans for q the listed near leaves whose boxes lie within the sink's bound: their squared
// distances to q (bucket_box_distance2()'s operations, lane by lane) 8 boxes at a time, the
// leaves within the bound as it stands then, each checked again against the bound as it has
// tightened by its turn.
template <class Sink>
inline __attribute__((always_inline)) void bucket_scan_near(const BucketView& v, const float* q,
                                                            const BucketRowScratch& s, Sink& sink) {
  const simd::Ints8 lane = {0, 1, 2, 3, 4, 5, 6, 7};
  const std::size_t listed = s.near.size();
  for (std::size_t c = 0; c < listed; c += 8) {
    Floats8 total{};
    for (int a = 0; a < 3; ++a) {
      Floats8 lo, hi;
      std::memcpy(&lo, s.lo[a].data() + c, sizeof lo);
      std::memcpy(&hi, s.hi[a].data() + c, sizeof hi);
      Floats8 below = lo - q[a], above = q[a] - hi;
      Floats8 d = below > above ? below : above;
      d = d > 0.0f ? d : Floats8{};
      if (a == 0)
        total = d * d;
      else
        total += d * d;
    }
    unsigned mask =
        bucket_lane_bits((total <= sink.worst()) & (lane < static_cast<int>(listed - c)));
    for (; mask != 0; mask &= mask - 1) {
      const unsigned j = static_cast<unsigned>(__builtin_ctz(mask));
      if (total[j] <= sink.worst()) bucket_scan_leaf(v, v.nodes[s.near[c + j]], q, sink);
    }
  }
}

// Squared distance as the leaf scan computes it (the same rounding): ((dx dx + dy dy) + dz dz).
inline float bucket_distance2(const float* q, const float* p) {
  const float dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
  float d = dx * dx;
  d += dy * dy;
  d += dz * dz;
  return d;
}

// The rows of the points of leaves [first, last) (of `leaves`, in leaf order), leaf by leaf.
// The leaves near each leaf (boxes within squared distance `bound` of its box: twice the
// largest squared k-th distance of the previous leaf's points) are listed once; each point
// scans its own leaf, then the listed leaves whose box lies within its current k-th distance.
// Exact: every point within the final k-th distance d of a point lies in a box within d of the
// leaf's box, so when d <= bound all of them were offered; a point whose d ends beyond `bound`
// is searched again from the root. Each search starts bounded by the farthest of the previous
// point's k neighbours (k points lie within it, so its k nearest do too).
template <class Knn>
inline __attribute__((always_inline)) void bucket_knn_leaves_with(
    const BucketView& v, const Eigen::Vector3f* points, const std::uint32_t* leaves,
    std::size_t first, std::size_t last, std::size_t k, std::size_t stride, std::uint32_t* indices,
    std::uint32_t* counts, BucketRowScratch& s) {
  const std::size_t slots = bucket_knn_slots(k);
  s.keys.resize(2 * slots);
  const std::uint32_t* previous = nullptr;  // the last full row
  float bound = std::numeric_limits<float>::infinity();
  {
    const BucketTree::Node& own = v.nodes[leaves[first]];
    const float q[3] = {v.xs[own.begin], v.ys[own.begin], v.zs[own.begin]};
    Knn probe(k, s.keys.data());
    bucket_search(v, q, probe);
    bound = 4.0f * probe.worst();
  }
  for (std::size_t l = first; l != last; ++l) {
    const std::uint32_t leaf = leaves[l];
    const BucketTree::Node& own = v.nodes[leaf];
    bucket_leaves_near(v, leaf, bound, s);
    float next_bound = 0.0f;
    for (std::uint32_t j = own.begin; j != own.begin + own.count; ++j) {
      const float q[3] = {v.xs[j], v.ys[j], v.zs[j]};
      float cap = std::numeric_limits<float>::infinity();
      if (previous != nullptr) {
        cap = 0.0f;
        for (std::size_t a = 0; a < k; ++a)
          cap = std::max(cap, bucket_distance2(q, points[previous[a]].data()));
      }
      Knn best(k, s.keys.data(), cap);
      bucket_scan_leaf(v, own, q, best);
      bucket_scan_near(v, q, s, best);
      const std::uint32_t id = v.ids[j];
      std::uint32_t* row = indices + static_cast<std::size_t>(id) * stride;
      if (best.worst() <= bound) {
        counts[id] = static_cast<std::uint32_t>(best.finish(row, nullptr));
      } else {  // points beyond `bound` may be missing: search again
        Knn again(k, s.keys.data() + slots, best.worst());
        bucket_search(v, q, again);
        counts[id] = static_cast<std::uint32_t>(again.finish(row, nullptr));
      }
      next_bound = std::max(next_bound, bucket_distance2(q, points[row[counts[id] - 1]].data()));
      previous = counts[id] == k ? row : nullptr;
    }
    bound = 2.0f * next_bound;  // margin: few points are searched again (kurt3d: 1.7 %)
  }
}

// bucket_knn_leaves_with() with k's k-best list: in registers for k = 10, unrolled for 9 to 12.
MESHFLOW_AVX2_CLONES void bucket_knn_leaves(const BucketView& v, const Eigen::Vector3f* points,
                                            const std::uint32_t* leaves, std::size_t first,
                                            std::size_t last, std::size_t k, std::size_t stride,
                                            std::uint32_t* indices, std::uint32_t* counts,
                                            BucketRowScratch& s) {
  if (k == 10)  // the normals' default (kn = ki = 10)
    bucket_knn_leaves_with<BucketKnnFixed<10>>(v, points, leaves, first, last, k, stride, indices,
                                               counts, s);
  else if ((k + 3) / 4 == 3)
    bucket_knn_leaves_with<BucketKnn<3>>(v, points, leaves, first, last, k, stride, indices, counts,
                                         s);
  else
    bucket_knn_leaves_with<BucketKnn<0>>(v, points, leaves, first, last, k, stride, indices, counts,
                                         s);
}

MESHFLOW_AVX2_CLONES void bucket_radius(const BucketView& v, const float* q, float squared_radius,
                                        std::vector<std::pair<std::uint32_t, float>>& hits) {
  BucketRadius sink(squared_radius, hits);
  bucket_search(v, q, sink);
}

}  // namespace

BucketTree::BucketTree(const std::vector<Eigen::Vector3f>& points) {
  const auto n = static_cast<std::uint32_t>(points.size());
  if (n == 0) return;
  int depth = 0;  // of the deepest leaf: the larger half is taken at every split
  for (std::uint32_t s = n; s > kLeafSize; s -= s / 2) ++depth;
  nodes_.resize((std::size_t{2} << depth) - 1);
  UninitVector<Item> items(n);  // first written by the threads below
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, n, 8192),
                    [&](const tbb::blocked_range<std::uint32_t>& r) {
                      for (std::uint32_t i = r.begin(); i != r.end(); ++i)
                        items[i] = {{points[i].x(), points[i].y(), points[i].z()}, i};
                    });
  build(0, 0, n, items.data());
  std::vector<std::uint32_t> stack = {0};  // the leaves in leaf order (depth first, left first)
  while (!stack.empty()) {
    const std::uint32_t node = stack.back();
    stack.pop_back();
    if (nodes_[node].count != 0) {
      leaves_.push_back(node);
    } else {
      stack.push_back(2 * node + 2);
      stack.push_back(2 * node + 1);
    }
  }
  // Written whole by the threads (no serial fill first), then the padding.
  xs_.resize(n + 8);
  ys_.resize(n + 8);
  zs_.resize(n + 8);
  ids_.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, n, 8192),
                    [&](const tbb::blocked_range<std::uint32_t>& r) {
                      for (std::uint32_t i = r.begin(); i != r.end(); ++i) {
                        xs_[i] = items[i].p[0];
                        ys_[i] = items[i].p[1];
                        zs_[i] = items[i].p[2];
                        ids_[i] = items[i].id;
                      }
                    });
  const float pad = std::numeric_limits<float>::quiet_NaN();  // never within any bound
  std::fill(xs_.begin() + n, xs_.end(), pad);
  std::fill(ys_.begin() + n, ys_.end(), pad);
  std::fill(zs_.begin() + n, zs_.end(), pad);
}

void BucketTree::build(std::size_t node, std::uint32_t begin, std::uint32_t end, Item* items) {
  static_assert(sizeof(Item) == 16, "an item is read as four floats");
  Node& nd = nodes_[node];
  // The box, the four floats of each item at once (the fourth, the index's bits, ignored).
  Floats4 lo = Floats4{} + std::numeric_limits<float>::infinity(), hi = -lo;
  for (std::uint32_t i = begin; i != end; ++i) {
    Floats4 p;
    std::memcpy(&p, &items[i], sizeof p);
    lo = p < lo ? p : lo;
    hi = p > hi ? p : hi;
  }
  for (int a = 0; a < 3; ++a) {
    nd.lo[a] = lo[a];
    nd.hi[a] = hi[a];
  }
  nd.lo[3] = nd.hi[3] = 0.0f;
  const std::uint32_t size = end - begin;
  if (size <= kLeafSize) {
    nd.begin = begin;
    nd.count = size;
    return;
  }
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (nd.hi[a] - nd.lo[a] > nd.hi[axis] - nd.lo[axis]) axis = a;
  const std::uint32_t middle = begin + size / 2;
  std::nth_element(items + begin, items + middle, items + end,
                   [axis](const Item& a, const Item& b) { return a.p[axis] < b.p[axis]; });
  const auto left = [&] { build(2 * node + 1, begin, middle, items); };
  const auto right = [&] { build(2 * node + 2, middle, end, items); };
  if (size >= kBucketParallelBuild) {
    tbb::parallel_invoke(left, right);
  } else {
    left();
    right();
  }
}

std::size_t BucketTree::knn(const Eigen::Vector3f& q, std::size_t k, std::uint32_t* indices,
                            float* squared_distances) const {
  k = std::min(k, size());
  if (k == 0) return 0;
  const BucketView v{nodes_.data(), xs_.data(), ys_.data(), zs_.data(), ids_.data()};
  return bucket_knn_one(v, q.data(), k, indices, squared_distances);
}

void BucketTree::radius(const Eigen::Vector3f& q, float squared_radius,
                        std::vector<std::pair<std::uint32_t, float>>& hits) const {
  if (size() == 0) return;
  const BucketView v{nodes_.data(), xs_.data(), ys_.data(), zs_.data(), ids_.data()};
  bucket_radius(v, q.data(), squared_radius, hits);
}

void BucketTree::knn_of_points(const std::vector<Eigen::Vector3f>& points, std::size_t k,
                               std::size_t stride, std::uint32_t* indices,
                               std::uint32_t* counts) const {
  k = std::min(k, size());
  if (k == 0) {
    std::fill(counts, counts + size(), 0u);
    return;
  }
  const BucketView v{nodes_.data(), xs_.data(), ys_.data(), zs_.data(), ids_.data()};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves_.size(), 16),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      BucketRowScratch scratch;
                      bucket_knn_leaves(v, points.data(), leaves_.data(), r.begin(), r.end(), k,
                                        stride, indices, counts, scratch);
                    });
}

}  // namespace meshflow::kd_tree
