#include "nodes/decimate/qem_decimation.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "nodes/decimate/collapse_fan.h"
#include "nodes/decimate/qem_finding_features.h"
#include "nodes/decimate/vertex_rings.h"
#include "runtime/angles.h"
#include "runtime/error.h"
#include "runtime/radix_sort.h"
#include "runtime/simd.h"

namespace meshflow {
namespace {

constexpr double kNoCollapse = std::numeric_limits<double>::infinity();
constexpr std::size_t kLookAhead = 8;  // collapses between a prefetch() and its use
// A pass walks its candidates up to this many times the bound of the candidate that would reach
// the target (Redwood frames: 1.5 took 6 passes, 2.5 takes 4 for the same deviation from the
// input; 3 and 4 deviate 1 and 2 % more).
constexpr double kPassLimit = 2.5;

// With independent collapses, a pass's limit is set by the candidate ranked at this fraction
// of the collapses still needed, not at all of them: each pass takes the cheapest collapses of
// every neighbourhood, as a one-at-a-time greedy would (1 / share, distance from the input,
// mean / p95 mm: kurt3d 1 1.314 / 5.098, 4 1.283 / 4.950, 8 1.266 / 4.794; synthetic room 1
// 0.179 / 0.647, 4 0.170 / 0.605, 8 0.168 / 0.597; more passes the larger it is).
constexpr std::size_t kIndependentShare = 4;

// cos(degrees), computed in double and rounded once.
float cos_degrees(float degrees) {
  return static_cast<float>(std::cos(radians(static_cast<double>(degrees))));
}

// Symmetric 4x4 quadric, upper triangle with the off-diagonal terms doubled (as they enter
// x^T A x): a2 2ab 2ac 2ad b2 2bc 2bd c2 2cd d2.
struct Quadric {
  double q[10] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0};

  static Quadric plane(const Eigen::Vector3d& n, double d, double weight) {
    Quadric k;
    const double p[4] = {n.x(), n.y(), n.z(), d};
    int i = 0;
    for (int r = 0; r < 4; ++r)
      for (int c = r; c < 4; ++c) k.q[i++] = (c == r ? 1.0 : 2.0) * (weight * p[r] * p[c]);
    return k;
  }
  void add(const Quadric& o) {
    for (int i = 0; i < 10; ++i) q[i] += o.q[i];
  }
  // x^T A x for x = (p, 1).
  double error(const Eigen::Vector3f& pf) const {
    const double* s = q;
    const double x = pf.x(), y = pf.y(), z = pf.z();
    return s[0] * x * x + s[1] * x * y + s[2] * x * z + s[3] * x + s[4] * y * y + s[5] * y * z +
           s[6] * y + s[7] * z * z + s[8] * z + s[9];
  }
};

// What an evaluation reads of each neighbour of u (its position for u's fan and, as a target,
// the rest), together: half a cache line.
struct alignas(32) VertexTerms {
  Eigen::Vector3f position;
  double own_error = 0.0;  ///< Q_v(v): (Q_u + Q_v)(v) = Q_u(v) + this
  double scale = 1.0;      ///< multiplies the quadric error (1 / depth^2, or 1)
};

using simd::Doubles4;

// The quadric cost of moving u onto each of `count` targets: costs[j] = max(0, (Q_u + Q_v)(v)) x
// scale_v for v = targets[j], with (Q_u + Q_v)(v) = Q_u(v) + own_error_v and `q_u` Q_u's ten
// terms. Four targets per vector, each lane Quadric::error()'s arithmetic in its order (neither
// fuses multiply-adds): the same values as one target at a time, in fewer instructions and with
// the four targets' loads in flight together.
MESHFLOW_AVX2_CLONES void quadric_costs(const Quadric& q_u, const VertexTerms* terms,
                                        const std::uint32_t* targets, std::size_t count,
                                        double* costs) {
  const double* s = q_u.q;
  for (std::size_t j = 0; j < count; j += 4) {
    const VertexTerms* t[4];  // a short last group repeats its first target
    for (std::size_t k = 0; k < 4; ++k) t[k] = &terms[targets[j + k < count ? j + k : j]];
    const Doubles4 x = {t[0]->position.x(), t[1]->position.x(), t[2]->position.x(),
                        t[3]->position.x()};
    const Doubles4 y = {t[0]->position.y(), t[1]->position.y(), t[2]->position.y(),
                        t[3]->position.y()};
    const Doubles4 z = {t[0]->position.z(), t[1]->position.z(), t[2]->position.z(),
                        t[3]->position.z()};
    const Doubles4 own = {t[0]->own_error, t[1]->own_error, t[2]->own_error, t[3]->own_error};
    const Doubles4 scale = {t[0]->scale, t[1]->scale, t[2]->scale, t[3]->scale};
    const Doubles4 sum = s[0] * x * x + s[1] * x * y + s[2] * x * z + s[3] * x + s[4] * y * y +
                         s[5] * y * z + s[6] * y + s[7] * z * z + s[8] * z + s[9] + own;
    const Doubles4 cost = (sum > 0.0 ? sum : Doubles4{}) * scale;  // as std::max(0.0, sum)
    for (std::size_t k = 0; k < 4 && j + k < count; ++k) costs[j + k] = cost[k];
  }
}

// One vertex u may move onto, in best_collapse(): its quadric cost, itself, and its index among
// u's targets (u's ring, where that index is its ring entry, or its two border neighbours).
struct Target {
  double cost;
  std::uint32_t v, at;
  // (cost, vertex) order; branch-free.
  bool before(const Target& o) const { return (cost < o.cost) | ((cost == o.cost) & (v < o.v)); }
};

// A vertex's numbers in a pass (collapses are numbered from 1 in each).
struct PassNumbers {
  /// The last collapse u -> v that changed the vertex's faces or quadric (it is u or one of u's
  /// neighbours, v among them); 0 = none.
  std::uint32_t changed = 0;
  /// For a vertex the walk evaluated again and left (over the pass's limit): the collapses
  /// before that evaluation, which its best collapse now holds (0 = it holds the pass's own).
  std::uint32_t evaluated = 0;
};

// The best collapse of one vertex, found at the start of a pass.
struct Candidate {
  double cost = kNoCollapse;
  std::uint32_t from = 0, to = 0;
};

// Sort key of a finite candidate: its cost as a float's bits (non-negative, so they order
// like the values), then its vertex in the low `vertex_bits` bits (as few as the vertex count
// needs: the radix sort skips the digits no key uses, one pass in six on a depth frame).
std::uint64_t order_key(const Candidate& c, int vertex_bits) {
  const float cost = static_cast<float>(c.cost);
  std::uint32_t bits = 0;
  std::memcpy(&bits, &cost, sizeof bits);
  return (std::uint64_t{bits} << vertex_bits) | c.from;
}

// Bits that hold every vertex number below `count`.
int bits_for(std::size_t count) {
  int bits = 1;
  while (bits < 32 && (std::size_t{1} << bits) < count) ++bits;
  return bits;
}

// A pass bounds the cost of every vertex that needs it on the mesh as it was when the pass
// started (neighbour rings, positions, quadrics), in parallel, then walks the bounds cheapest
// first, evaluating each candidate fully before it is applied. Each collapse u -> v removes u; v
// takes over u's faces (VertexRings::collapse), and v's quadric and u's neighbours' faces change:
// a candidate with an end among them is evaluated again on the mesh as it is now and taken while
// its cost stays within the pass's limit. The walk goes in chunks: the evaluations a chunk needs
// run in parallel at its start, and again, serially, only where a collapse earlier in the chunk
// changed the ends once more. The next pass bounds again only the vertices next to a change.
class Decimator {
 public:
  // The setup that needs no feature edges: rings (from `around`, vertex_triangles(mesh)),
  // positions, scales, face quadrics. constrain() must follow before run().
  Decimator(const TriangleMesh& mesh, const VertexTriangles& around, const QemConfig& config)
      : in_(mesh),
        cfg_(config),
        rings_(mesh.triangles, around),
        q_(mesh.vertices.size()),
        terms_(mesh.vertices.size()),
        cos_turn_(cos_degrees(config.max_normal_turn_deg)),
        cos_border_(cos_degrees(config.max_border_turn_deg)),
        cos_sharp_(cos_degrees(config.sharp_edge_deg)),
        cos2_min_angle_(static_cast<float>(
            std::pow(std::cos(radians(static_cast<double>(config.min_angle_deg))), 2))),
        scratch_([this] { return Scratch(*this); }) {
    // The caller's locked vertices (QemConfig::locked) join the rings' own.
    for (std::size_t v = 0; v < config.locked.size(); ++v)
      if (config.locked[v] != 0) rings_.lock(static_cast<std::uint32_t>(v));
    // Per vertex its position (it never changes) and 1 / depth^2 (or 1).
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, mesh.vertices.size()),
        [&](const tbb::blocked_range<std::size_t>& range) {
          for (std::size_t v = range.begin(); v != range.end(); ++v) {
            terms_[v].position = mesh.vertices[v];
            if (config.divide_by_depth2)
              terms_[v].scale =
                  1.0 / std::max(1e-6, static_cast<double>(
                                           (mesh.vertices[v] - config.viewpoint).squaredNorm()));
          }
        });
    // The area-weighted plane quadrics of every vertex's faces, summed in face order: on one
    // thread, face by face into their corners; else every face's plane first, then per vertex
    // in parallel (`around` lists its faces ascending). The same sums either way.
    const bool one_thread =
        std::min<std::size_t>(
            tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism),
            static_cast<std::size_t>(tbb::this_task_arena::max_concurrency())) <= 1;
    if (one_thread) {
      for (const Triangle& t : mesh.triangles) {
        const FacePlane f = face_plane(t);
        if (!(f.weight > 0.0)) continue;
        const Quadric k = Quadric::plane(f.unit, f.d, f.weight);
        for (std::uint32_t v : t) q_[v].add(k);
      }
      return;
    }
    std::vector<FacePlane> planes(mesh.triangles.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, planes.size()),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t f = range.begin(); f != range.end(); ++f)
                          planes[f] = face_plane(mesh.triangles[f]);
                      });
    tbb::parallel_for(
        tbb::blocked_range<std::uint32_t>(0, static_cast<std::uint32_t>(mesh.vertices.size())),
        [&](const tbb::blocked_range<std::uint32_t>& range) {
          for (std::uint32_t v = range.begin(); v != range.end(); ++v)
            for (const std::uint32_t* f = around.begin(v); f != around.end(v); ++f)
              if (planes[*f].weight > 0.0)
                q_[v].add(Quadric::plane(planes[*f].unit, planes[*f].d, planes[*f].weight));
        });
  }

  // The rest of the setup: the feature edges' lines and constraint quadrics (none when empty),
  // then every vertex's own error (in parallel).
  void constrain(const std::vector<std::array<std::uint32_t, 2>>& feature_edges) {
    if (!feature_edges.empty()) add_feature_constraints(feature_edges);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, in_.vertices.size()),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t v = range.begin(); v != range.end(); ++v)
                          terms_[v].own_error = q_[v].error(p(static_cast<std::uint32_t>(v)));
                      });
  }

  // Decimates to at most `target` faces, or until no collapse is valid, in passes (see the
  // class comment): mark the vertices a pass changed, bound their costs, sort, walk. Returns the
  // mesh that remains, vertices compacted.
  TriangleMesh run(std::size_t target, QemReport& report) {
    start(target);
    bool stalled = false;  // the last pass collapsed nothing
    while (alive_ > target_) {
      if (!targets_.empty()) mark_changed_vertices();
      targets_.clear();
      bound_marked_costs();
      if (!(cfg_.independent_collapses ? gather_candidates() : sort_candidates())) break;
      bool evaluated = false;  // (independent collapses: the pass evaluated a candidate)
      const std::size_t collapsed =
          cfg_.independent_collapses ? independent_pass(evaluated) : walk_pass();
      report.collapses += collapsed;
      ++report.passes;
      // A pass may collapse nothing when every candidate it walked cost more, evaluated, than its
      // bound let the limit reach; all of them are evaluated now, so the next pass, evaluating
      // nothing, takes the cheapest. A second pass without a collapse: none is valid. (With
      // independent collapses, only the chosen ones are evaluated: a pass that evaluated some
      // is no stall.)
      if (collapsed == 0) {
        if (!evaluated) {
          if (stalled) break;
          stalled = true;
        }
        std::fill(dirty_.begin(), dirty_.end(), 0);
      } else {
        stalled = false;
      }
    }
    add_refusals(report);
    report.collapse_sequence = std::move(sequence_);
    // Faces come out of the rings rotated and reordered (VertexRings::triangles()); when
    // nothing collapsed, the input's faces are returned as given.
    if (report.collapses == 0) return compact_vertices(in_, in_.triangles);
    return compact_vertices(in_, rings_.triangles());
  }

 private:
  // The feature lines (line_, feature_degree_) and, at both ends of every feature edge, its
  // constraint planes: through the edge, perpendicular to each of its faces, weighted by
  // penalty x length^2 (serial, in face order: the sums must not depend on the thread count).
  void add_feature_constraints(const std::vector<std::array<std::uint32_t, 2>>& edges) {
    const std::size_t n = in_.vertices.size();
    feature_degree_.assign(n, 0);
    line_.assign(n, {0, 0});
    std::vector<std::uint64_t> keys;
    keys.reserve(edges.size());
    for (const auto& e : edges) {
      if (e[0] >= n || e[1] >= n || e[0] == e[1]) continue;
      keys.push_back(undirected_edge_key(e[0], e[1]));
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    for (std::uint64_t key : keys) {
      const auto a = static_cast<std::uint32_t>(key >> 32), b = static_cast<std::uint32_t>(key);
      const std::array<std::uint32_t, 2> ends[2] = {{a, b}, {b, a}};
      for (const auto& [x, y] : ends) {
        if (feature_degree_[x] < 2) line_[x][feature_degree_[x]] = y;
        if (feature_degree_[x] < 255) ++feature_degree_[x];
      }
    }
    for (const Triangle& t : in_.triangles) {
      // Most faces touch no feature edge: a corner off every line rules all three edges out.
      const int on_lines = (feature_degree_[t[0]] != 0) + (feature_degree_[t[1]] != 0) +
                           (feature_degree_[t[2]] != 0);
      if (on_lines < 2) continue;
      const Eigen::Vector3d a = p(t[0]).cast<double>();
      const Eigen::Vector3d normal =
          (p(t[1]).cast<double>() - a).cross(p(t[2]).cast<double>() - a).normalized();
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t x = t[k], y = t[(k + 1) % 3];
        if (feature_degree_[x] == 0 || feature_degree_[y] == 0 ||
            !std::binary_search(keys.begin(), keys.end(), undirected_edge_key(x, y)))
          continue;
        const Eigen::Vector3d px = p(x).cast<double>(), along = p(y).cast<double>() - px;
        const Eigen::Vector3d side = along.cross(normal);
        const double length2 = along.squaredNorm();
        if (!(side.squaredNorm() > 0.0) || !normal.allFinite()) continue;
        const Eigen::Vector3d unit = side.normalized();
        const Quadric k2 = Quadric::plane(unit, -unit.dot(px), cfg_.penalty * length2);
        q_[x].add(k2);
        q_[y].add(k2);
      }
    }
  }

  // A face's plane through its first corner and its quadric weight (half its area; 0 for a
  // face without area, which adds nothing).
  struct FacePlane {
    Eigen::Vector3d unit = Eigen::Vector3d::Zero();
    double d = 0.0, weight = 0.0;
  };
  FacePlane face_plane(const Triangle& t) const {
    const Eigen::Vector3d a = in_.vertices[t[0]].cast<double>();
    const Eigen::Vector3d n =
        (in_.vertices[t[1]].cast<double>() - a).cross(in_.vertices[t[2]].cast<double>() - a);
    const double area2 = n.norm();
    if (!(area2 > 0.0)) return {};
    const Eigen::Vector3d unit = n / area2;
    return {unit, -unit.dot(a), 0.5 * area2};
  }

  // Whether u lies on a feature edge (with features given).
  bool on_feature(std::uint32_t u) const {
    return !feature_degree_.empty() && feature_degree_[u] != 0;
  }

  // Phase 0: the run's state, every vertex marked for a bound.
  void start(std::size_t target) {
    const std::size_t n = in_.vertices.size();
    target_ = target;
    alive_ = in_.triangles.size();
    best_.assign(n, Candidate{});
    pass_.assign(n, PassNumbers{});
    dirty_.assign(n, 1);
    validated_.assign(n, 0);
    targets_.clear();
    order_.clear();
    vertex_bits_ = bits_for(n);
    vertex_mask_ = (std::uint64_t{1} << vertex_bits_) - 1;
  }

  // Phase 1: marks the vertices whose best collapse the last pass may have changed.
  // After u -> v, exactly the vertices of v's faces need a new best collapse: a vertex w's
  // best reads its own faces (changed only around v), its neighbours' quadrics (only v's
  // changed) and, for the link condition of w -> x, the common neighbours of w and x,
  // which change only when w was next to u or is next to v.
  // Of those, a vertex w that was not next to any u of the pass (no `changed` number) kept its
  // faces; only costs towards a v grew and link conditions towards vertices next to a u
  // could fail. So its best collapse w -> y stays the best unless y changed (next to a
  // u, or a v), and a w with no valid collapse keeps none: neither is re-evaluated.
  // "Changed" counts from w's last evaluation: for a w the walk evaluated again, only the
  // collapses after that one (the same output as evaluating it again, for less work).
  void mark_changed_vertices() {
    std::fill(dirty_.begin(), dirty_.end(), 0);
    const auto mark_dirty = [&](std::uint32_t x) {
      dirty_[x] = pass_[x].changed > pass_[x].evaluated ||
                  (best_[x].cost < kNoCollapse && pass_[best_[x].to].changed > pass_[x].evaluated);
    };
    for (std::size_t j = 0; j < targets_.size(); ++j) {
      // (Targets lie all over the mesh: their rings are requested ahead.)
      if (j + 2 * kLookAhead < targets_.size()) rings_.prefetch_slot(targets_[j + 2 * kLookAhead]);
      if (j + kLookAhead < targets_.size()) rings_.prefetch_ring(targets_[j + kLookAhead]);
      const std::uint32_t v = targets_[j];
      if (rings_.face_count(v) == 0) continue;  // collapsed later in the pass
      mark_dirty(v);
      for (const std::uint32_t* x = rings_.begin(v); x != rings_.end(v); ++x)
        if (*x != VertexRings::kSeparator) mark_dirty(*x);
    }
  }

  // Phase 2: a lower bound of the best collapse of every marked vertex, in parallel on the mesh
  // as the pass starts.
  // After the first pass the marked vertices are few and apart (next to the last pass's
  // collapses): a range's are listed first, and each one's ring, quadric and its neighbours'
  // terms requested ahead, in three stages (each from addresses the one before brought in).
  void bound_marked_costs() {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, best_.size()),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        Scratch& scratch = local_scratch();  // a lookup: once per range
                        std::vector<std::uint32_t>& marked = scratch.marked;
                        marked.clear();
                        for (std::size_t u = range.begin(); u != range.end(); ++u)
                          if (dirty_[u]) marked.push_back(static_cast<std::uint32_t>(u));
                        const std::size_t count = marked.size();
                        for (std::size_t i = 0; i < count; ++i) {
                          if (i + 2 * kLookAhead < count)
                            rings_.prefetch_slot(marked[i + 2 * kLookAhead]);
                          if (i + kLookAhead < count) prefetch_bound(marked[i + kLookAhead]);
                          const std::uint32_t u = marked[i];
                          best_[u] = cost_bound(u, scratch);
                          validated_[u] = 0;
                        }
                      });
  }

  // Requests what cost_bound(u) reads besides u's ring (requested earlier): u's quadric and
  // its neighbours' terms.
  void prefetch_bound(std::uint32_t u) const {
    __builtin_prefetch(&q_[u].q[0]);
    __builtin_prefetch(&q_[u].q[8]);
    for (const std::uint32_t* x = rings_.begin(u); x != rings_.end(u); ++x)
      if (*x != VertexRings::kSeparator) __builtin_prefetch(&terms_[*x]);
  }

  // Phase 3: the candidates cheapest first, as keys (cost as float bits, vertex), radix-sorted;
  // non-negative floats order as their bit patterns, equal costs by vertex. (A comparison sort of
  // the candidates was 8 % of the decimation.) False when no vertex has a collapse.
  bool sort_candidates() {
    if (!gather_candidates()) return false;
    radix_sort(order_);
    return true;
  }

  // Phase 3 with independent collapses: the candidates' keys, unordered (independent_pass()
  // orders only those it needs), in vertex order: in blocks of vertices, in parallel, each
  // block's candidates counted, then written at the block's place (the counts' prefix sums).
  // False when no vertex has a collapse.
  bool gather_candidates() {
    constexpr std::size_t kBlockVertices = 8192;
    const std::size_t blocks = (best_.size() + kBlockVertices - 1) / kBlockVertices;
    block_starts_.assign(blocks + 1, 0);
    const auto block_range = [&](std::size_t block) {
      return std::make_pair(block * kBlockVertices,
                            std::min(best_.size(), (block + 1) * kBlockVertices));
    };
    tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t block) {
      const auto [first, last] = block_range(block);
      std::size_t count = 0;
      for (std::size_t u = first; u < last; ++u) count += best_[u].cost < kNoCollapse ? 1 : 0;
      block_starts_[block + 1] = count;
    });
    for (std::size_t block = 0; block < blocks; ++block)
      block_starts_[block + 1] += block_starts_[block];
    order_.resize(block_starts_[blocks]);
    tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t block) {
      const auto [first, last] = block_range(block);
      std::uint64_t* to = order_.data() + block_starts_[block];
      for (std::size_t u = first; u < last; ++u)
        if (best_[u].cost < kNoCollapse) *to++ = order_key(best_[u], vertex_bits_);
    });
    return !order_.empty();
  }

  // The i-th candidate of the pass's order.
  const Candidate& candidate(std::size_t i) const { return best_[order_[i] & vertex_mask_]; }

  // Phase 4: the walk. Greedy within the pass, but only up to kPassLimit x the bound of the
  // collapse that would reach the target if every collapse removed two faces, so cheap collapses
  // elsewhere get their turn in the next pass before expensive ones are taken here. In chunks of
  // walk_chunk candidates (0: the whole walk, re-evaluating serially). Returns the collapses.
  std::size_t walk_pass() {
    const std::size_t goal = std::min(order_.size(), (alive_ - target_ + 1) / 2);
    Walk walk;
    walk.limit = kPassLimit * candidate(std::max<std::size_t>(goal, 1) - 1).cost;
    std::fill(pass_.begin(), pass_.end(), PassNumbers{});
    const bool ahead_in_parallel = cfg_.walk_chunk != 0;
    const std::size_t chunk = ahead_in_parallel ? cfg_.walk_chunk : order_.size();
    ahead_.resize(ahead_in_parallel ? chunk : 0);
    has_ahead_.resize(ahead_.size());
    for (std::size_t first = 0; first < order_.size() && !walk.stop; first += chunk) {
      const std::size_t last = std::min(order_.size(), first + chunk);
      walk.chunk_start = walk.clock;
      std::fill(has_ahead_.begin(), has_ahead_.end(), 0);
      if (ahead_in_parallel) evaluate_ahead(first, last, walk);
      walk_chunk(first, last, ahead_in_parallel, walk);
    }
    return walk.collapsed;
  }

  // A walk's running numbers.
  struct Walk {
    double limit = 0.0;             ///< the pass's cost limit
    std::size_t collapsed = 0;      ///< collapses in the pass
    std::uint32_t clock = 0;        ///< collapses so far in the pass, numbering them
    std::uint32_t chunk_start = 0;  ///< `clock` when the chunk started
    bool stop = false;              ///< the target or the limit is reached
  };

  // The chunk's candidates that hold a bound or whose ends changed since their evaluation,
  // evaluated in parallel on the mesh as it is now (nothing changes it meanwhile).
  void evaluate_ahead(std::size_t first, std::size_t last, const Walk& walk) {
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(first, last, 16),
        [&](const tbb::blocked_range<std::size_t>& range) {
          Scratch& local = local_scratch();
          // The range's candidates to evaluate are listed first, then what each evaluation reads
          // is requested a few evaluations ahead, in stages (as the serial walk's, but counted
          // in evaluations: most candidates need none).
          std::vector<std::uint32_t>& due = local.marked;
          due.clear();
          for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const Candidate& c = candidate(i);
            if (c.cost > walk.limit ||
                (validated_[c.from] && !pass_[c.from].changed && !pass_[c.to].changed))
              continue;
            due.push_back(static_cast<std::uint32_t>(i));
          }
          const std::size_t count = due.size();
          for (std::size_t k = 0; k < count; ++k) {
            if (k + kLookAhead < count) prefetch(candidate(due[k + kLookAhead]), false);
            if (k + kLookAhead / 2 < count) prefetch_corners(candidate(due[k + kLookAhead / 2]));
            const std::size_t i = due[k];
            has_ahead_[i - first] = 1;
            ahead_[i - first] = best_collapse(candidate(i).from, local);
          }
        });
  }

  // The walk goes in cost order, all over the mesh: what a collapse a few steps ahead of
  // candidate i reads is requested now (2-9 % of the decimation on a noisy depth frame). A serial
  // walk also evaluates most of its candidates again, reading u's whole neighbourhood: that is
  // requested in three stages, each from addresses the previous one brought in (another ~8 % on
  // a Redwood frame; with chunks, evaluated ahead in parallel, it was slower).
  void prefetch_walk(std::size_t i, bool ahead_in_parallel) const {
    const std::size_t n = order_.size();
    if (ahead_in_parallel) {
      // Evaluated at the chunk's start: u's ring is near; what the collapse itself then reads
      // and writes, u's neighbours' records (their rings) and numbers, in one more stage.
      if (i + kLookAhead < n) prefetch(candidate(i + kLookAhead), false);
      if (i + kLookAhead / 2 < n) prefetch_corners(candidate(i + kLookAhead / 2));
      return;
    }
    if (i + 3 * kLookAhead < n)
      __builtin_prefetch(&best_[order_[i + 3 * kLookAhead] & vertex_mask_]);
    if (i + 2 * kLookAhead < n) prefetch_slots(candidate(i + 2 * kLookAhead));
    if (i + kLookAhead < n) prefetch(candidate(i + kLookAhead), true);
    if (i + kLookAhead / 2 < n) prefetch_corners(candidate(i + kLookAhead / 2));
  }

  // Walks candidates [first, last): each is taken, if it is still valid and within the limit
  // on the mesh as it is now, or kept for the next pass.
  void walk_chunk(std::size_t first, std::size_t last, bool ahead_in_parallel, Walk& walk) {
    Scratch& scratch = local_scratch();
    for (std::size_t i = first; i < last; ++i) {
      prefetch_walk(i, ahead_in_parallel);
      Candidate c = candidate(i);
      if (alive_ <= target_ || (c.cost > walk.limit && walk.collapsed > 0)) {
        walk.stop = true;
        return;
      }
      std::uint32_t evaluated_at = 0;  // the pass's evaluation
      if (ahead_in_parallel && has_ahead_[i - first]) {
        c = ahead_[i - first];
        evaluated_at = walk.chunk_start;
        validated_[c.from] = 1;
      }
      // A bound, or u or its target took part in a collapse, or lost a neighbour, since the
      // evaluation: u's best collapse on the mesh as it is now, with every check. Taken if it
      // stays within the limit (else u waits for the next pass).
      if (!validated_[c.from] || pass_[c.from].changed > evaluated_at ||
          (c.cost < kNoCollapse && pass_[c.to].changed > evaluated_at)) {
        c = best_collapse(c.from, scratch);
        evaluated_at = walk.clock;
        validated_[c.from] = 1;
      }
      if (!(c.cost <= walk.limit)) {  // kept: the next pass re-evaluates it only if it changes
        best_[c.from] = c;
        pass_[c.from].evaluated = evaluated_at;
        continue;
      }
      alive_ -= collapse(c.from, c.to, ++walk.clock, pass_);
      if (cfg_.record_collapses) sequence_.push_back({c.from, c.to});
      targets_.push_back(c.to);
      best_[c.from].cost = kNoCollapse;  // removed
      ++walk.collapsed;
    }
  }

  // Phase 4 with independent collapses. The pass's limit: kPassLimit x the bound of the
  // candidate whose rank is 1 / kIndependentShare of the collapses still needed. Candidates
  // within it, cheapest first (their bounds, or their costs where evaluated: the walk's order),
  // are chosen unless a vertex of u's closed neighbourhood (u and its ring) is in that of one
  // chosen before; the chosen ones are evaluated fully, in parallel on the mesh as the pass
  // starts, and taken, in that order, where they stay within the limit. Disjoint neighbourhoods
  // keep every evaluation exact for the mesh the others leave (a collapse reads and writes only
  // its own: collapse()), so the taken ones are applied together, in parallel. Returns the
  // collapses; sets `evaluated` when it evaluated any candidate.
  std::size_t independent_pass(bool& evaluated) {
    const std::size_t goal = std::min(order_.size(), (alive_ - target_ + 1) / 2);
    const std::size_t rank = std::max<std::size_t>(1, goal / kIndependentShare);
    std::nth_element(order_.begin(), order_.begin() + static_cast<std::ptrdiff_t>(rank - 1),
                     order_.end());
    const double limit = kPassLimit * candidate(rank - 1).cost;
    std::fill(pass_.begin(), pass_.end(), PassNumbers{});
    picks_.clear();
    for (std::uint64_t key : order_)
      if (best_[key & vertex_mask_].cost <= limit) picks_.push_back(key);
    radix_sort(picks_);
    // Chosen cheapest first while their closed neighbourhoods stay apart (claimed_ holds the
    // pass's stamp on those chosen).
    if (claimed_.size() != best_.size()) claimed_.assign(best_.size(), 0);
    if (++pass_stamp_ == 0) {  // wrapped around: start the stamps again
      std::fill(claimed_.begin(), claimed_.end(), 0);
      pass_stamp_ = 1;
    }
    chosen_.clear();
    evaluated = false;
    // The picks lie all over the mesh: each one's slot, ring and claims are requested ahead,
    // in three stages (each from addresses the one before brought in).
    const auto pick = [&](std::size_t i) {
      return static_cast<std::uint32_t>(picks_[i] & vertex_mask_);
    };
    for (std::size_t i = 0; i < picks_.size(); ++i) {
      if (i + 2 * kLookAhead < picks_.size()) rings_.prefetch_slot(pick(i + 2 * kLookAhead));
      if (i + kLookAhead < picks_.size()) rings_.prefetch_ring(pick(i + kLookAhead));
      if (i + kLookAhead / 2 < picks_.size()) {
        const std::uint32_t w = pick(i + kLookAhead / 2);
        __builtin_prefetch(&claimed_[w]);
        for (const std::uint32_t* x = rings_.begin(w); x != rings_.end(w); ++x)
          __builtin_prefetch(&claimed_[*x]);
      }
      const std::uint32_t u = pick(i);
      bool apart = claimed_[u] != pass_stamp_;
      for (const std::uint32_t* x = rings_.begin(u); x != rings_.end(u); ++x)
        apart &= claimed_[*x] != pass_stamp_;
      if (!apart) continue;
      claimed_[u] = pass_stamp_;
      for (const std::uint32_t* x = rings_.begin(u); x != rings_.end(u); ++x)
        claimed_[*x] = pass_stamp_;
      chosen_.push_back(u);
      evaluated |= validated_[u] == 0;
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chosen_.size(), 16),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        Scratch& local = local_scratch();
                        for (std::size_t i = range.begin(); i != range.end(); ++i) {
                          const std::uint32_t u = chosen_[i];
                          if (validated_[u]) continue;
                          best_[u] = best_collapse(u, local);
                          validated_[u] = 1;
                        }
                      });
    taken_.clear();
    for (std::uint32_t u : chosen_) {
      if (alive_ <= target_) break;
      Candidate& c = best_[u];
      if (!(c.cost <= limit)) continue;  // kept: the next pass evaluates it only if it changes
      rings_.reserve_collapse(u, c.to);
      alive_ -= rings_.kind(u) == VertexRings::Kind::kOpen ? 1 : 2;
      taken_.push_back({u, c.to});
      targets_.push_back(c.to);
      c.cost = kNoCollapse;  // removed
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, taken_.size(), 32),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t j = range.begin(); j != range.end(); ++j)
                          collapse(taken_[j][0], taken_[j][1], static_cast<std::uint32_t>(j + 1),
                                   pass_);
                      });
    if (cfg_.record_collapses) sequence_.insert(sequence_.end(), taken_.begin(), taken_.end());
    return taken_.size();
  }

  // Phase 5: the refusals every thread counted.
  void add_refusals(QemReport& report) const {
    for (const Scratch& scratch : scratch_) {
      report.rejected_topology += scratch.rejected.rejected_topology;
      report.rejected_normal += scratch.rejected.rejected_normal;
      report.rejected_border += scratch.rejected.rejected_border;
      report.rejected_feature += scratch.rejected.rejected_feature;
    }
  }

  const Eigen::Vector3f& p(std::uint32_t v) const { return terms_[v].position; }

  // Per-thread working memory of best_collapse().
  struct Scratch {
    explicit Scratch(const Decimator& d) : fan(d.cos_turn_, d.cos2_min_angle_) {}
    const std::uint32_t* neighbours = nullptr;  ///< u's ring
    std::size_t neighbour_count = 0;
    std::uint32_t border[2] = {0, 0};  ///< u's neighbours along its border, if it is on one
    std::size_t border_count = 0;      ///< 2 on a border, else 0
    std::uint32_t line[2] = {0, 0};    ///< u's neighbours along its feature line, if on one
    bool on_line = false;              ///< u is an inner vertex or a loose end of a feature line
    std::size_t line_count = 0;        ///< 2 for an inner vertex, 1 for a loose end
    std::vector<Target> candidates;    ///< u's targets by quadric cost
    std::vector<double> costs;         ///< quadric_costs() of u's targets
    /// bound_marked_costs(): a range's marked vertices; evaluate_ahead(): a range's candidates
    /// to evaluate
    std::vector<std::uint32_t> marked;
    CollapseFan fan;  ///< u's faces

    // The quadric costs of moving u onto each of its `count` targets (see quadric_costs()).
    const double* target_costs(const Decimator& d, std::uint32_t u, const std::uint32_t* targets,
                               std::size_t count) {
      if (costs.size() < count) costs.resize(2 * count);
      quadric_costs(d.q_[u], d.terms_.data(), targets, count, costs.data());
      return costs.data();
    }

    QemReport rejected;  ///< refusals counted by this thread
  };

  // This thread's Scratch.
  Scratch& local_scratch() { return scratch_.local(); }

  // The vertices u may move onto: its neighbours (scratch.neighbours, the ring), or on a
  // border only its two border neighbours (scratch.border): a border vertex may only move along
  // its border (see valid()), and only where the border runs nearly straight through it; both
  // moves make the same turn, so a bend rules out both before any cost is computed (counted as
  // refused). Returns their number and sets `targets`; 0 when u has no faces, is locked or sits
  // on a bend.
  std::size_t movable_targets(std::uint32_t u, Scratch& scratch,
                              const std::uint32_t*& targets) const {
    scratch.neighbour_count = 0;
    scratch.border_count = 0;
    scratch.on_line = false;
    scratch.line_count = 0;
    if (rings_.face_count(u) == 0 || rings_.locked(u)) return 0;
    const std::uint32_t* const ring = rings_.begin(u);
    const std::size_t n = rings_.size(u);
    scratch.neighbours = ring;
    scratch.neighbour_count = n;
    targets = ring;
    if (on_feature(u)) {  // a corner stays; a line vertex moves along its line
      if (feature_degree_[u] == 1 && rings_.kind(u) == VertexRings::Kind::kClosed) {
        scratch.line[0] = line_[u][0];  // a loose end (noise, not a corner) shortens its line
        scratch.on_line = true;
        scratch.line_count = 1;
        targets = scratch.line;
        return 1;
      }
      // (A bend is priced by the feature quadrics, not refused: a scanned room's junction
      // lines zigzag by more than the border limit and must still simplify.)
      if (feature_degree_[u] != 2 || rings_.kind(u) != VertexRings::Kind::kClosed) {
        ++scratch.rejected.rejected_feature;
        return 0;
      }
      scratch.line[0] = line_[u][0];
      scratch.line[1] = line_[u][1];
      scratch.on_line = true;
      scratch.line_count = 2;
      targets = scratch.line;
      return 2;
    }
    if (rings_.kind(u) != VertexRings::Kind::kOpen) return n;
    scratch.border[0] = ring[0];
    scratch.border[1] = ring[n - 1];
    scratch.border_count = 2;
    if (!border_straight(u, ring[0], ring[n - 1])) {
      scratch.rejected.rejected_border += 2;
      return 0;
    }
    targets = scratch.border;
    return 2;
  }

  // A lower bound of best_collapse(u): the cheapest quadric cost over the vertices u may move
  // onto, without the fan's checks, the link condition and the penalties (which only raise
  // costs). kNoCollapse when u may not move.
  Candidate cost_bound(std::uint32_t u, Scratch& scratch) const {
    Candidate bound;
    bound.from = u;
    const std::uint32_t* targets = nullptr;
    const std::size_t count = movable_targets(u, scratch, targets);
    const double* const costs = scratch.target_costs(*this, u, targets, count);
    for (std::size_t j = 0; j < count; ++j) {
      const double cost = costs[j];
      if (cost < bound.cost || (cost == bound.cost && targets[j] < bound.to)) {
        bound.cost = cost;
        bound.to = targets[j];
      }
    }
    return bound;
  }

  // The cheapest valid collapse u -> v over u's neighbours v (cost kNoCollapse when none), on
  // u's faces as they are now.
  Candidate best_collapse(std::uint32_t u, Scratch& scratch) const {
    Candidate best;
    best.from = u;
    const std::uint32_t* targets = nullptr;
    const std::size_t count = movable_targets(u, scratch, targets);
    if (count == 0) return best;
    const std::uint32_t* const ring = rings_.begin(u);
    const std::size_t n = rings_.size(u), faces = rings_.face_count(u);
    if (scratch.candidates.size() < n) scratch.candidates.resize(2 * n);
    Target* const queue = scratch.candidates.data();
    const double* const costs = scratch.target_costs(*this, u, targets, count);
    for (std::size_t j = 0; j < count; ++j)
      queue[j] = Target{costs[j], targets[j], static_cast<std::uint32_t>(j)};
    // u's faces (u, r[k], r[k + 1]), each neighbour's position read once (after the border
    // test: a bent border needs no fan).
    CollapseFan& fan = scratch.fan;
    fan.reset(faces, p(u));
    const Eigen::Vector3f* pa = &p(ring[0]);
    for (std::size_t k = 0; k < faces; ++k) {
      const std::uint32_t b = ring[k + 1 == n ? 0 : k + 1];
      const Eigen::Vector3f* pb = &p(b);
      fan.set(k, ring[k], *pa, b, *pb);
      pa = pb;
    }
    fan.finish(faces);
    // Penalties only multiply the quadric cost, so candidates are tried in the order of
    // (quadric cost, vertex) until it alone exceeds the best penalised cost found. Most
    // evaluations stop after one or two, so each is picked when needed, the cheapest of those
    // left (branch-free), rather than all sorted first. The targets are distinct and no cost is
    // NaN (quadric_costs() maps NaN to 0): the order is total.
    for (std::size_t left = count; left != 0;) {
      std::size_t cheapest = 0;
      for (std::size_t k = 1; k < left; ++k)
        cheapest = queue[k].before(queue[cheapest]) ? k : cheapest;
      const auto [quadric, v, at] = queue[cheapest];
      queue[cheapest] = queue[--left];
      if (!(quadric < best.cost)) break;
      const FanVerdict verdict = fan.check(v, p(v));
      if (verdict.turned) {  // invalid whatever the cost: refused before anything else
        ++scratch.rejected.rejected_normal;
        continue;
      }
      const double cost = scratch.on_line ? (verdict.needle ? quadric * cfg_.penalty : quadric)
                                          : penalised(fan, n, at, verdict, quadric);
      if (!(cost < best.cost)) continue;
      if (!valid(v, verdict, scratch)) continue;
      best.cost = cost;
      best.to = v;
    }
    return best;
  }

  // Requests the memory that evaluating and applying c reads: the quadrics of its ends, v's
  // position, and their rings: with `slots_in_cache` (prefetch_slots() ran earlier) directly,
  // else after their slots.
  void prefetch(const Candidate& c, bool slots_in_cache) const {
    for (std::uint32_t x : {c.from, c.to}) {
      __builtin_prefetch(&q_[x].q[0]);
      __builtin_prefetch(&q_[x].q[8]);  // a quadric spans two cache lines
    }
    __builtin_prefetch(&terms_[c.to]);
    if (!slots_in_cache) {  // (a record holds most rings: the rest are not waited for)
      prefetch_slots(c);
      return;
    }
    rings_.prefetch_ring(c.from);
    rings_.prefetch_ring(c.to);
  }

  // Requests the ring slots (offset, size) of c's ends.
  void prefetch_slots(const Candidate& c) const {
    rings_.prefetch_slot(c.from);
    rings_.prefetch_slot(c.to);
  }

  // Requests the terms (position, target terms) and ring records of u's neighbours
  // (prefetch(c, true) ran earlier, so u's ring is in cache).
  void prefetch_corners(const Candidate& c) const {
    for (const std::uint32_t* x = rings_.begin(c.from); x != rings_.end(c.from); ++x) {
      __builtin_prefetch(&terms_[*x]);
      __builtin_prefetch(&pass_[*x]);
      rings_.prefetch_slot(*x);
    }
  }

  // Whether the border w -> u -> v turns by less than max_border_turn_deg at u (the same for
  // v -> u -> w).
  bool border_straight(std::uint32_t u, std::uint32_t w, std::uint32_t v) const {
    const Eigen::Vector3f in = (p(u) - p(w)).normalized(), out = (p(v) - p(u)).normalized();
    return in.dot(out) >= cos_border_;
  }

  // The quadric cost times the penalty where the edge is sharp (its two faces, around u, differ
  // by more than sharp_edge_deg) or a needle would appear (a face (v, a, b) replacing (u, a, b)
  // with an inner angle below min_angle_deg). v is u's target `at`: an edge with two faces
  // belongs to a closed ring of `n` (a border vertex moves only onto its border neighbours, which
  // share one face with it), whose targets are the ring, so faces at - 1 and at (around) hold v.
  double penalised(const CollapseFan& fan, std::size_t n, std::size_t at, const FanVerdict& verdict,
                   double cost) const {
    if (verdict.needle) return cost * cfg_.penalty;
    if (verdict.shared != 2) return cost;
    const std::size_t before = at == 0 ? n - 1 : at - 1;
    const bool bent = fan.bent_between(std::min(before, at), std::max(before, at), cos_sharp_);
    return bent ? cost * cfg_.penalty : cost;
  }

  // Whether u -> v keeps the mesh manifold and borders on themselves (see QemConfig), for the
  // u whose neighbourhood and fan `scratch` holds; `verdict` is the fan's check of v (its faces
  // that stay are unturned: the caller checked). Counts the reason of a refusal.
  bool valid(std::uint32_t v, const FanVerdict& verdict, Scratch& scratch) const {
    const std::uint32_t* border_at_u = scratch.border;
    const std::size_t border_count = scratch.border_count;
    QemReport& rejected = scratch.rejected;
    const std::size_t shared_count = verdict.shared;
    if (shared_count == 0 || shared_count > 2) {
      ++rejected.rejected_topology;
      return false;
    }
    // Borders: u on a border moves only along it, onto the next border vertex (best_collapse()
    // has checked that the border runs nearly straight there).
    if (border_count != 0) {
      const bool along =
          shared_count == 1 && border_count == 2 && (border_at_u[0] == v || border_at_u[1] == v);
      if (!along) {
        ++rejected.rejected_border;
        return false;
      }
    }
    // A feature line of three vertices would close into two: u's other line neighbour must
    // not already be v's.
    if (scratch.on_line && scratch.line_count == 2 && feature_degree_[v] == 2) {
      const std::uint32_t w = scratch.line[0] == v ? scratch.line[1] : scratch.line[0];
      if (line_[v][0] == w || line_[v][1] == w) {
        ++rejected.rejected_feature;
        return false;
      }
    }
    // A border u of one face (an ear: only with max_border_turn_deg above 90) takes that face
    // along; its other two corners must keep a face each, or they would be left with none.
    if (scratch.neighbour_count == 2) {
      for (std::size_t j = 0; j < 2; ++j)
        if (rings_.face_count(scratch.neighbours[j]) < 2) {
          ++rejected.rejected_topology;
          return false;
        }
    }
    // (Faces that stay must not flip, degenerate or turn beyond the limit: `verdict.turned`,
    // refused by best_collapse() before the cost.)
    // Link condition (last: the dearest check): the common neighbours are exactly the edge's
    // opposite vertices (u's ring lists distinct vertices, v among them).
    const std::size_t common =
        rings_.neighbours_among(v, scratch.neighbours, scratch.neighbour_count);
    if (common != shared_count) {
      ++rejected.rejected_topology;
      return false;
    }
    // The link's edges: only an inner u of three faces can share one with v, the edge between
    // its other two neighbours; if that edge has a face with v, the four faces close a
    // tetrahedron and the collapse would fold u's last face onto that one.
    if (shared_count == 2 && scratch.neighbour_count == 3) {
      std::uint32_t others[2] = {0, 0};
      std::size_t k = 0;
      for (std::size_t j = 0; j < 3; ++j)
        if (scratch.neighbours[j] != v) others[k++ & 1] = scratch.neighbours[j];
      if (rings_.share_face(v, others[0], others[1])) {
        ++rejected.rejected_topology;
        return false;
      }
    }
    return true;
  }

  // Applies u -> v, the pass's collapse `number`, and writes that number as `changed` for u
  // and its neighbours (v among them): the vertices whose faces or quadric change. Returns the
  // faces removed (one on a border edge, two inside). Writes only the state of u's closed
  // neighbourhood (u and its ring): collapses of disjoint ones may run in parallel, each after
  // VertexRings::reserve_collapse().
  std::size_t collapse(std::uint32_t u, std::uint32_t v, std::uint32_t number,
                       std::vector<PassNumbers>& pass) {
    pass[u].changed = number;
    for (const std::uint32_t* x = rings_.begin(u); x != rings_.end(u); ++x)
      pass[*x].changed = number;
    if (on_feature(u) && feature_degree_[u] == 1) {  // a loose end: v loses that edge
      if (feature_degree_[v] == 2 && line_[v][0] == u) line_[v][0] = line_[v][1];
      if (feature_degree_[v] <= 2) --feature_degree_[v];
    } else if (on_feature(u)) {  // u -> v along the line w - u - v: the line runs w - v now
      const std::uint32_t w = line_[u][0] == v ? line_[u][1] : line_[u][0];
      const std::array<std::uint32_t, 3> moves[2] = {{v, u, w}, {w, u, v}};
      for (const auto& [x, from, to] : moves)
        if (feature_degree_[x] == 2) (line_[x][0] == from ? line_[x][0] : line_[x][1]) = to;
    }
    const std::size_t removed = rings_.collapse(u, v);
    q_[v].add(q_[u]);
    terms_[v].own_error = q_[v].error(p(v));
    return removed;
  }

  const TriangleMesh& in_;
  const QemConfig& cfg_;
  VertexRings rings_;                                   ///< the mesh as it is now
  std::vector<std::array<std::uint32_t, 2>> sequence_;  ///< collapses applied, if recorded
  std::vector<Quadric> q_;
  std::vector<VertexTerms> terms_;
  /// With feature edges: per vertex their number (saturating at 255; empty without features),
  /// and for a vertex with two, its two neighbours along the line (kept current by collapse()).
  std::vector<std::uint8_t> feature_degree_;
  std::vector<std::array<std::uint32_t, 2>> line_;
  float cos_turn_, cos_border_, cos_sharp_, cos2_min_angle_;
  mutable tbb::enumerable_thread_specific<Scratch> scratch_;  ///< best_collapse()'s memory

  // A run's state (start()).
  std::size_t target_ = 0, alive_ = 0;  ///< faces wanted, faces left
  std::vector<Candidate> best_;         ///< per vertex: its best collapse, or a bound of it
  std::vector<PassNumbers> pass_;       ///< per vertex, in a pass (read together: side by side)
  /// dirty_: the vertex needs a new bound; validated_: best_[u] is u's best collapse, fully
  /// evaluated (else a lower bound of its cost). (A vertex is listed once per pass, so a
  /// removed one is never met again in it.)
  std::vector<std::uint8_t> dirty_, validated_;
  std::vector<std::uint32_t> targets_;     ///< the kept vertex of every collapse of the last pass
  std::vector<std::uint64_t> order_;       ///< a pass's candidates, cheapest first (order_key())
  std::vector<std::size_t> block_starts_;  ///< gather_candidates(): where each block's keys go
  int vertex_bits_ = 0;
  std::uint64_t vertex_mask_ = 0;
  std::vector<Candidate> ahead_;         ///< a chunk's candidates evaluated in parallel
  std::vector<std::uint8_t> has_ahead_;  ///< 1 where ahead_ holds one
  // independent_pass()'s memory:
  std::vector<std::uint64_t> picks_;    ///< candidates within the limit, cheapest first
  std::vector<std::uint32_t> chosen_;   ///< u of the candidates chosen, in that order
  std::vector<std::uint32_t> claimed_;  ///< pass_stamp_ on the closed neighbourhoods taken
  std::uint32_t pass_stamp_ = 0;
  std::vector<std::array<std::uint32_t, 2>> taken_;  ///< the pass's collapses {u, v}
};

}  // namespace

TriangleMesh qem_decimate(const TriangleMesh& mesh, const QemConfig& config, QemReport* report) {
  return qem_decimate(mesh, {}, config, report);
}

TriangleMesh qem_decimate(const TriangleMesh& mesh,
                          const std::vector<std::array<std::uint32_t, 2>>& feature_edges,
                          const QemConfig& config, QemReport* report) {
  return qem_decimate_finding_features(
      mesh,
      [&feature_edges](const VertexTriangles&) -> const QemFeatureEdges& { return feature_edges; },
      config, report);
}

TriangleMesh qem_decimate_finding_features(
    const TriangleMesh& mesh,
    const std::function<const QemFeatureEdges&(const VertexTriangles&)>& find_features,
    const QemConfig& config, QemReport* report) {
  require_corners_in_range(mesh.triangles, mesh.vertices.size(), "QEM decimation");
  if (!config.locked.empty() && config.locked.size() != mesh.vertices.size())
    throw Error("QEM decimation", "locked vertices",
                std::to_string(config.locked.size()) + " flags for " +
                    std::to_string(mesh.vertices.size()) + " vertices");
  QemReport r;
  const auto target = static_cast<std::size_t>(std::ceil(
      static_cast<double>(mesh.triangles.size()) * static_cast<double>(config.target_ratio)));
  std::optional<Decimator> decimator;
  const QemFeatureEdges* feature_edges = nullptr;
  {
    const VertexTriangles around = vertex_triangles(mesh);  // the rings' and the features'
    tbb::parallel_invoke([&] { decimator.emplace(mesh, around, config); },
                         [&] { feature_edges = &find_features(around); });
  }
  decimator->constrain(*feature_edges);
  TriangleMesh out = decimator->run(target, r);
  if (report != nullptr) *report = r;
  return out;
}

}  // namespace meshflow
