#include "nodes/normals/orient_normals.h"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <numeric>
#include <type_traits>

#include "runtime/parallel.h"
#include "runtime/radix_sort.h"

namespace meshflow {
namespace {

// Signs (+1, -1) chosen for the unoriented normals.
using Signs = std::vector<std::int8_t>;

// Each normal replaced by the principal axis of its neighbours' normals' outer products (a
// sign-free average over the table row), found by two power iterations from the normal itself,
// which is close to that axis. Noisy plane fits disagree by tens of degrees between neighbours,
// and a tree built on them sends wrong signs across whole regions (measured: 6 % of normals
// wrong on a noisy box with a hole, 0.2 % after this); the averaged axes vary smoothly.
// Parallel over points; O(n k).
std::vector<Eigen::Vector3f> tensor_smoothed(const std::vector<Eigen::Vector3f>& n,
                                             const NeighbourTable& t) {
  std::vector<Eigen::Vector3f> out(n.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n.size(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        Eigen::Matrix3f tensor = Eigen::Matrix3f::Zero();
                        for (std::uint32_t j = 0; j < t.counts[i]; ++j) {
                          const Eigen::Vector3f& v = n[t.row(i)[j]];
                          tensor.noalias() += v * v.transpose();
                        }
                        Eigen::Vector3f axis = n[i];
                        for (int iteration = 0; iteration < 2; ++iteration) {
                          const Eigen::Vector3f next = tensor * axis;
                          const float length = next.norm();
                          if (!(length > 0.0f)) break;
                          axis = next / length;
                        }
                        out[i] = axis;  // T n_i . n_i >= 0: still on n_i's side
                      }
                    });
  return out;
}

// The neighbour graph's edges, one per table entry e = i * k + slot (point i's slot-th
// neighbour), as 16-bit codes: the edge's weight 1 - |m_i . m_j| quantised to kLevels levels,
// plus kOppositeBit when m_i . m_j < 0 (the ends' normals point opposite ways). An entry that is
// no edge (the point itself, an unused slot, or the second listing of an edge that both ends
// list, so that each edge is offered to the spanning forest once) is kNoEdge. Two bytes per
// entry: on a fresh process every page touched costs a fault, and this is the largest array.
constexpr std::uint16_t kLevels = 2048;
constexpr std::uint16_t kOppositeBit = 0x4000;
constexpr std::uint16_t kLevelMask = kLevels - 1;
constexpr std::uint16_t kNoEdge = 0xffff;

std::vector<std::uint16_t> edge_codes(const std::vector<Eigen::Vector3f>& m,
                                      const NeighbourTable& t) {
  std::vector<std::uint16_t> codes(t.indices.size());
  // Whether `of` lists `wanted`; branch-free over the whole row so that it vectorises.
  auto lists = [&t](std::uint32_t of, std::uint32_t wanted) {
    const std::uint32_t* row = t.row(of);
    const std::uint32_t count = t.counts[of];
    bool hit = false;
    for (std::uint32_t j = 0; j < t.k; ++j) hit |= (row[j] == wanted) & (j < count);
    return hit;
  };
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, t.size(), 2048),
      [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const auto self = static_cast<std::uint32_t>(i);
          const std::uint32_t* row = t.row(i);
          std::uint16_t* out = codes.data() + i * t.k;
          for (std::uint32_t j = 0; j < t.k; ++j) {
            const std::uint32_t other = row[j];
            if (j >= t.counts[i] || other == self || (other < self && lists(other, self))) {
              out[j] = kNoEdge;
              continue;
            }
            const float c = m[i].dot(m[other]);
            const auto level = static_cast<std::uint16_t>(
                std::clamp(1.0f - std::abs(c), 0.0f, 1.0f) * (kLevels - 1) + 0.5f);
            out[j] = static_cast<std::uint16_t>(level | (c < 0.0f ? kOppositeBit : 0));
          }
        }
      });
  return codes;
}

// The edges' entries in Kruskal's order: by weight level, ties in table order, each with its
// kOppositeBit moved to the entry's top bit (read here in parallel rather than in the serial
// loop). Entries must leave the top bit free.
template <typename Entry>
constexpr Entry kEntryOpposite = Entry{1} << (8 * sizeof(Entry) - 1);

template <typename Entry>
std::vector<Entry> edges_by_weight(const std::vector<std::uint16_t>& codes) {
  return counting_sort<Entry>(
      codes.size(), kLevels,
      [&codes](std::size_t e) {
        return codes[e] == kNoEdge ? std::size_t{kLevels}
                                   : static_cast<std::size_t>(codes[e] & kLevelMask);
      },
      [&codes](std::size_t e) {
        const auto entry = static_cast<Entry>(e);
        return (codes[e] & kOppositeBit) != 0 ? entry | kEntryOpposite<Entry> : entry;
      });
}

// Exact e / k for e < 2^31 and 1 <= k < 2^16 by a multiply and a shift: with s = 32 +
// ceil(log2 k) and m = ceil(2^s / k), e m / 2^s exceeds e / k by less than 1 / (2k), so the
// floor is the quotient. Keeps a division out of the serial loop.
struct SmallDivisor {
  std::uint64_t multiplier;
  int shift;
  explicit SmallDivisor(std::uint64_t k) {
    assert(k >= 1 && k < (1u << 16));
    int log = 0;
    while ((std::uint64_t{1} << log) < k) ++log;
    shift = 32 + log;
    multiplier = ((std::uint64_t{1} << shift) + k - 1) / k;
  }
  std::uint64_t divide(std::uint32_t e) const { return (e * multiplier) >> shift; }
};

// Union-find whose elements carry their parity (1 = opposite sign) relative to their set's
// root, so that the spanning forest and the propagation of signs along it are one pass: an edge
// joining two sets fixes the parity between their roots. The root of every set is its lowest
// index (deterministic). Not thread-safe; near-constant time per call.
class SignedSets {
 public:
  // Elements up to 2^31 (the link's top bit holds the parity).
  explicit SignedSets(std::size_t n) : link_(n) {
    assert(n < kParityBit);
    std::iota(link_.begin(), link_.end(), 0u);
  }

  // The root of x's set; `parity` receives x's parity to it. Path halving: each element passed
  // is linked to its grandparent, with the parity of the two steps combined.
  std::uint32_t find(std::uint32_t x, std::uint8_t& parity) {
    std::uint32_t to_root = 0;
    while (parent(x) != x) {
      const std::uint32_t up = link_[parent(x)];
      link_[x] = (up & kParentMask) | ((link_[x] ^ up) & kParityBit);
      to_root ^= link_[x];
      x = link_[x] & kParentMask;
    }
    parity = static_cast<std::uint8_t>(to_root >> 31);
    return x;
  }

  // Joins the sets of roots ra and rb (distinct) so that parity(a) ^ parity(b) == opposite,
  // given a's parity pa to ra and b's parity pb to rb.
  void unite(std::uint32_t ra, std::uint8_t pa, std::uint32_t rb, std::uint8_t pb,
             std::uint8_t opposite) {
    const std::uint32_t root = std::min(ra, rb), child = std::max(ra, rb);
    link_[child] = root | (static_cast<std::uint32_t>(pa ^ pb ^ opposite) << 31);
  }

  // Every element's root and parity to it, without changing the sets. Parallel, read-only.
  void roots(std::vector<std::uint32_t>& root, std::vector<std::uint8_t>& parity) const {
    root.resize(link_.size());
    parity.resize(link_.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, link_.size(), 8192),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t i = r.begin(); i != r.end(); ++i) {
                          auto x = static_cast<std::uint32_t>(i);
                          std::uint32_t p = 0;
                          while (parent(x) != x) {
                            p ^= link_[x];
                            x = parent(x);
                          }
                          root[i] = x;
                          parity[i] = static_cast<std::uint8_t>(p >> 31);
                        }
                      });
  }

 private:
  static constexpr std::uint32_t kParityBit = 0x80000000u;
  static constexpr std::uint32_t kParentMask = kParityBit - 1;
  std::uint32_t parent(std::uint32_t x) const { return link_[x] & kParentMask; }

  std::vector<std::uint32_t> link_;  // parent index | parity to the parent << 31
};

// Kruskal over the edges in weight order (most confident first): each edge that joins two
// trees joins them so that its ends agree. Serial; near-constant-time finds per edge.
template <typename Entry>
SignedSets spanning_forest(const NeighbourTable& t, const std::vector<Entry>& order) {
  const std::size_t n = t.size();
  SignedSets sets(n);
  const SmallDivisor row_of(std::is_same_v<Entry, std::uint32_t> ? t.k : 1);
  std::size_t joined = 0;
  for (const Entry tagged : order) {
    if (joined + 1 >= n) break;
    const Entry e = tagged & ~kEntryOpposite<Entry>;
    const auto point = static_cast<std::uint32_t>(
        std::is_same_v<Entry, std::uint32_t> ? row_of.divide(e) : e / t.k);
    std::uint8_t pa = 0, pb = 0;
    const std::uint32_t ra = sets.find(point, pa);
    const std::uint32_t rb = sets.find(t.indices[e], pb);
    if (ra == rb) continue;
    sets.unite(ra, pa, rb, pb, (tagged & kEntryOpposite<Entry>) != 0 ? 1 : 0);
    ++joined;
  }
  return sets;
}

// The signed spanning forest of the graph with 32-bit entry numbers where they suffice.
SignedSets signed_forest(const std::vector<Eigen::Vector3f>& smooth, const NeighbourTable& t) {
  const std::vector<std::uint16_t> codes = edge_codes(smooth, t);
  if (codes.size() < (std::size_t{1} << 31) && t.k < (1u << 16))
    return spanning_forest(t, edges_by_weight<std::uint32_t>(codes));
  return spanning_forest(t, edges_by_weight<std::uint64_t>(codes));
}

// The components of the forest: each point's component number (0, 1, ... in the order of
// their lowest point) and the count.
struct Components {
  std::vector<std::uint32_t> of;  // per point
  std::size_t count = 0;
};

Components number_components(const std::vector<std::uint32_t>& root) {
  const std::vector<std::uint32_t> roots =
      parallel_select_indices(root.size(), [&](std::size_t i) { return root[i] == i; });
  std::vector<std::uint32_t> number_of_root(root.size(), 0);
  for (std::size_t c = 0; c < roots.size(); ++c)
    number_of_root[roots[c]] = static_cast<std::uint32_t>(c);
  Components out;
  out.count = roots.size();
  out.of.resize(root.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, root.size(), 8192),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        out.of[i] = number_of_root[root[i]];
                    });
  return out;
}

// Signs from the parities: within a component all relative to its root; the root's own sign
// is +1, or, where the component holds fixed points, the one that makes its lowest fixed point
// +1. Fixed points are +1 whatever their parity (their sign is given).
Signs signs_from_parity(const std::vector<std::uint8_t>& parity, const Components& comps,
                        const std::vector<std::uint8_t>& fixed) {
  std::vector<std::uint8_t> root_parity(comps.count, 0), decided(comps.count, 0);
  for (std::size_t i = 0; i < fixed.size(); ++i) {
    if (!fixed[i] || decided[comps.of[i]]) continue;
    decided[comps.of[i]] = 1;
    root_parity[comps.of[i]] = parity[i];
  }
  Signs sign(parity.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, parity.size(), 8192),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        const bool flipped = (parity[i] ^ root_parity[comps.of[i]]) != 0;
                        sign[i] = (!fixed.empty() && fixed[i]) || !flipped ? 1 : -1;
                      }
                    });
  return sign;
}

// One Jacobi vote: a free point whose signed agreement with its neighbours sums below zero
// turns over. Returns the number turned.
std::size_t vote(const NeighbourTable& t, const std::vector<Eigen::Vector3f>& smooth,
                 const std::vector<std::uint8_t>& fixed, Signs& sign) {
  const std::size_t count = t.size();
  const std::size_t blocks = (count + kParallelBlock - 1) / kParallelBlock;
  Signs next(count);
  std::vector<std::size_t> turned(blocks, 0);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    const std::size_t end = std::min(count, (b + 1) * kParallelBlock);
    for (std::size_t i = b * kParallelBlock; i < end; ++i) {
      next[i] = sign[i];
      if (!fixed.empty() && fixed[i]) continue;
      const std::uint32_t* row = t.row(i);
      Eigen::Vector3f sum = Eigen::Vector3f::Zero();
      for (std::uint32_t j = 0; j < t.counts[i]; ++j)
        if (row[j] != i) sum += static_cast<float>(sign[row[j]]) * smooth[row[j]];
      if (static_cast<float>(sign[i]) * smooth[i].dot(sum) < 0.0f) {
        next[i] = static_cast<std::int8_t>(-sign[i]);
        ++turned[b];
      }
    }
  });
  sign.swap(next);
  std::size_t total = 0;
  for (std::size_t c : turned) total += c;
  return total;
}

// Per-component sums for the side rules.
struct ComponentSums {
  Eigen::Vector3d position_sum = Eigen::Vector3d::Zero();
  double points = 0.0, signed_sum = 0.0, absolute_sum = 0.0;  // n . (p - centroid)
  double toward_sum = 0.0, toward_absolute = 0.0;             // n . (point - p) / |point - p|
  double along_sum = 0.0, along_absolute = 0.0;               // n . axis
  std::uint32_t extreme = std::numeric_limits<std::uint32_t>::max();  // point of largest x
  bool has_fixed = false;
};

// `add(sums, i)` over every point into per-component sums: per fixed block of points in
// parallel when there are few components, joined in block order (deterministic), else serial.
template <typename Add, typename Join>
std::vector<ComponentSums> accumulate(const Components& comps, std::vector<ComponentSums> sums,
                                      Add add, Join join) {
  const std::size_t n = comps.of.size();
  const std::size_t blocks = (n + kParallelBlock - 1) / kParallelBlock;
  if (comps.count > 64) {
    for (std::size_t i = 0; i < n; ++i) add(sums[comps.of[i]], i);
    return sums;
  }
  std::vector<std::vector<ComponentSums>> partial(blocks, sums);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    const std::size_t end = std::min(n, (b + 1) * kParallelBlock);
    for (std::size_t i = b * kParallelBlock; i < end; ++i) add(partial[b][comps.of[i]], i);
  });
  for (const auto& block : partial)
    for (std::size_t c = 0; c < sums.size(); ++c) join(sums[c], block[c]);
  return sums;
}

// A component inside an odd number of larger ones (the wall of a cavity, the inner shell of a
// hollow ball) bounds the solid from within: its normals must face its own centroid. Counted
// with the generalized winding number (Jacobson et al. 2013) of each larger component, facing
// outward, at the smaller one's centroid: sum over its points of a_i n_i . (p_i - q) /
// (4 pi |p_i - q|^3), 1 inside a closed surface and 0 outside, with a_i the area a point stands
// for (pi d_k^2 / k from its k-th neighbour's distance d_k). Components without a fixed point
// only; up to 64 components (O(n x components)), beyond that every one faces outward.
void turn_nested_components_inward(const std::vector<Eigen::Vector3f>& p,
                                   const std::vector<Eigen::Vector3f>& n, const NeighbourTable& t,
                                   const Components& comps,
                                   const std::vector<Eigen::Vector3d>& centroid,
                                   const std::vector<ComponentSums>& sums, Signs& sign) {
  const std::size_t count = comps.count;
  if (count < 2 || count > 64) return;
  // Sizes: the bounding-box diagonal of each component's points.
  std::vector<Eigen::AlignedBox3f> box(count);
  for (std::size_t i = 0; i < p.size(); ++i) box[comps.of[i]].extend(p[i]);
  std::vector<float> size(count);
  for (std::size_t c = 0; c < count; ++c) size[c] = box[c].sizes().norm();
  auto larger = [&size](std::size_t d, std::size_t c) {
    return size[d] > size[c] || (size[d] == size[c] && d < c);
  };
  // winding[c * count + d]: component d's winding number at c's centroid, in fixed blocks.
  const std::size_t blocks = (p.size() + kParallelBlock - 1) / kParallelBlock;
  std::vector<std::vector<double>> partial(blocks, std::vector<double>(count * count, 0.0));
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    std::vector<double>& w = partial[b];
    const std::size_t end = std::min(p.size(), (b + 1) * kParallelBlock);
    for (std::size_t i = b * kParallelBlock; i < end; ++i) {
      if (t.counts[i] < 2) continue;
      const std::size_t d = comps.of[i];
      const Eigen::Vector3d pi = p[i].cast<double>();
      const double reach2 = (p[t.row(i)[t.counts[i] - 1]].cast<double>() - pi).squaredNorm();
      const double area = M_PI * reach2 / static_cast<double>(t.counts[i]);
      const Eigen::Vector3d ni = sign[i] * n[i].cast<double>();
      for (std::size_t c = 0; c < count; ++c) {
        if (!larger(d, c)) continue;
        const Eigen::Vector3d r = pi - centroid[c];
        const double len = r.norm();
        if (len > 0.0) w[c * count + d] += area * ni.dot(r) / (4.0 * M_PI * len * len * len);
      }
    }
  });
  std::vector<std::uint8_t> inward(count, 0);
  for (std::size_t c = 0; c < count; ++c) {
    if (sums[c].has_fixed) continue;
    long depth = 0;
    for (std::size_t d = 0; d < count; ++d) {
      double w = 0.0;
      for (const auto& block : partial) w += block[c * count + d];
      depth += std::lround(w);
    }
    inward[c] = (depth & 1) != 0 ? 1 : 0;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, p.size(), 8192),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        if (inward[comps.of[i]]) sign[i] = static_cast<std::int8_t>(-sign[i]);
                    });
}

// Turns every component without a fixed point to the side `config.side` asks for (see the
// header) and returns the rule applied (kViewOrOutward resolved).
ComponentSide turn_components(const std::vector<Eigen::Vector3f>& p,
                              const std::vector<Eigen::Vector3f>& n, const NeighbourTable& t,
                              const Components& comps, const std::vector<std::uint8_t>& fixed,
                              const PropagationConfig& config, Signs& sign,
                              double& view_agreement) {
  auto larger_x = [&p](std::uint32_t a, std::uint32_t b) {  // b beats a (ties: lower index)
    const std::uint32_t none = std::numeric_limits<std::uint32_t>::max();
    return a == none || (b != none && (p[b].x() > p[a].x() || (p[b].x() == p[a].x() && b < a)));
  };
  std::vector<ComponentSums> sums = accumulate(
      comps, std::vector<ComponentSums>(comps.count),
      [&](ComponentSums& s, std::size_t i) {
        s.position_sum += p[i].cast<double>();
        s.points += 1.0;
        if (larger_x(s.extreme, static_cast<std::uint32_t>(i)))
          s.extreme = static_cast<std::uint32_t>(i);
        if (!fixed.empty() && fixed[i]) s.has_fixed = true;
      },
      [&](ComponentSums& into, const ComponentSums& from) {
        into.position_sum += from.position_sum;
        into.points += from.points;
        if (larger_x(into.extreme, from.extreme)) into.extreme = from.extreme;
        into.has_fixed = into.has_fixed || from.has_fixed;
      });
  std::vector<Eigen::Vector3d> centroid(comps.count);
  for (std::size_t c = 0; c < comps.count; ++c) centroid[c] = sums[c].position_sum / sums[c].points;
  const Eigen::Vector3d point = config.point.cast<double>();
  const Eigen::Vector3d axis = config.axis.cast<double>().normalized();
  sums = accumulate(
      comps, std::move(sums),
      [&](ComponentSums& s, std::size_t i) {
        const Eigen::Vector3d ni = sign[i] * n[i].cast<double>();
        const Eigen::Vector3d pi = p[i].cast<double>();
        const double d = ni.dot(pi - centroid[comps.of[i]]);
        s.signed_sum += d;
        s.absolute_sum += std::abs(d);
        const Eigen::Vector3d to_point = point - pi;
        const double distance = to_point.norm();
        const double facing = distance > 0.0 ? ni.dot(to_point) / distance : 0.0;
        s.toward_sum += facing;
        s.toward_absolute += std::abs(facing);
        s.along_sum += ni.dot(axis);
        s.along_absolute += std::abs(ni.dot(axis));
      },
      [&](ComponentSums& into, const ComponentSums& from) {
        into.signed_sum += from.signed_sum;
        into.absolute_sum += from.absolute_sum;
        into.toward_sum += from.toward_sum;
        into.toward_absolute += from.toward_absolute;
        into.along_sum += from.along_sum;
        into.along_absolute += from.along_absolute;
      });
  // One view from the point (one surface along the axis): each component, once facing it,
  // agrees with itself on facing it.
  const auto agreement = [&sums](double ComponentSums::*sum, double ComponentSums::*absolute) {
    double agreeing = 0.0, total = 0.0;
    for (const ComponentSums& s : sums) {
      agreeing += std::abs(s.*sum);
      total += s.*absolute;
    }
    return total > 0.0 ? agreeing / total : 0.0;
  };
  ComponentSide side = config.side;
  if (side == ComponentSide::kViewOrOutward) {
    view_agreement = agreement(&ComponentSums::toward_sum, &ComponentSums::toward_absolute);
    side = view_agreement >= config.min_view_agreement ? ComponentSide::kTowardPoint
                                                       : ComponentSide::kOutward;
  } else if (side == ComponentSide::kAxisOrOutward) {
    view_agreement = agreement(&ComponentSums::along_sum, &ComponentSums::along_absolute);
    side = view_agreement >= config.min_view_agreement ? ComponentSide::kAlongAxis
                                                       : ComponentSide::kOutward;
  }
  std::vector<std::uint8_t> flip(comps.count, 0);
  for (std::size_t c = 0; c < comps.count; ++c) {
    const ComponentSums& s = sums[c];
    if (s.has_fixed) continue;
    const bool extreme_faces_minus_x = sign[s.extreme] * n[s.extreme].x() < 0.0f;
    switch (side) {
      case ComponentSide::kTowardPoint:
        flip[c] = s.toward_sum != 0.0 ? s.toward_sum < 0.0 : extreme_faces_minus_x;
        break;
      case ComponentSide::kAlongAxis:
        flip[c] = s.along_sum != 0.0 ? s.along_sum < 0.0 : extreme_faces_minus_x;
        break;
      case ComponentSide::kOutward:
      case ComponentSide::kViewOrOutward:
      case ComponentSide::kAxisOrOutward: {
        const bool decisive = std::abs(s.signed_sum) > 0.05 * s.absolute_sum;
        flip[c] = decisive ? s.signed_sum < 0.0 : extreme_faces_minus_x;
        break;
      }
    }
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, p.size(), 8192),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        if (flip[comps.of[i]]) sign[i] = static_cast<std::int8_t>(-sign[i]);
                    });
  if (side == ComponentSide::kOutward)
    turn_nested_components_inward(p, n, t, comps, centroid, sums, sign);
  return side;
}

}  // namespace

OrientedNormals orient_by_propagation(const std::vector<Eigen::Vector3f>& positions,
                                      const std::vector<Eigen::Vector3f>& normals,
                                      const NeighbourTable& neighbours,
                                      const std::vector<std::uint8_t>& fixed,
                                      const PropagationConfig& config) {
  assert(normals.size() == positions.size() && neighbours.size() == positions.size());
  assert(fixed.empty() || fixed.size() == positions.size());
  OrientedNormals out;
  if (positions.empty()) return out;
  const std::vector<Eigen::Vector3f> smooth = tensor_smoothed(normals, neighbours);
  const SignedSets forest = signed_forest(smooth, neighbours);
  std::vector<std::uint32_t> root;
  std::vector<std::uint8_t> parity;
  forest.roots(root, parity);
  const Components comps = number_components(root);
  out.components = comps.count;
  Signs sign = signs_from_parity(parity, comps, fixed);
  for (int pass = 0; pass < config.vote_passes; ++pass) {
    const std::size_t turned = vote(neighbours, smooth, fixed, sign);
    out.flipped_by_vote += turned;
    if (turned == 0) break;
  }
  out.side = turn_components(positions, normals, neighbours, comps, fixed, config, sign,
                             out.view_agreement);
  out.normals.resize(positions.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, positions.size(), 8192),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        out.normals[i] = static_cast<float>(sign[i]) * normals[i];
                    });
  return out;
}

}  // namespace meshflow
