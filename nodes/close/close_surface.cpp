#include "nodes/close/close_surface.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <functional>
#include <iterator>
#include <memory>
#include <utility>
#include <vector>

#include "nodes/close/gradient_fill.h"
#include "nodes/close/through_lines.h"
#include "runtime/error.h"
#include "runtime/voxel_key.h"

namespace meshflow {
namespace {

// The [t0, t1] part of the segment o + t d (t in [0, t_end]) inside the box [lo, hi]; false
// when it misses.
bool close_clip_segment(const Eigen::Vector3f& o, const Eigen::Vector3f& d, float t_end,
                        const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, float& t0,
                        float& t1) {
  t0 = 0.0f;
  t1 = t_end;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0f) {
      if (o[a] < lo[a] || o[a] > hi[a]) return false;
      continue;
    }
    float ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t0 <= t1;
}

// A box of lattice nodes: node i stands for the grid corner origin + step * i (corner indices
// as in SparseGrid::corners), i in [0, size).
struct NodeBox {
  Eigen::Vector3i origin = Eigen::Vector3i::Zero();
  int step = 1;
  Eigen::Vector3i size = Eigen::Vector3i::Zero();
};

// Seen-empty marks of `box`'s nodes: each line of sight is sampled at t = k x (step / 2)
// voxels from the sensor (the same samples whichever box is marked, so tiles sharing a face
// mark it alike), up to `stop` metres before its point; a sample marks its nearest node.
// Idempotent stores: any thread order marks the same nodes.
std::unique_ptr<std::atomic<std::uint8_t>[]> close_sight_marks(const PointCloud& cloud,
                                                               const NodeBox& box, float voxel,
                                                               float stop) {
  const std::size_t nodes = static_cast<std::size_t>(box.size.x()) * box.size.y() * box.size.z();
  std::unique_ptr<std::atomic<std::uint8_t>[]> marks(new std::atomic<std::uint8_t>[nodes]);
  for (std::size_t n = 0; n < nodes; ++n) marks[n].store(0, std::memory_order_relaxed);
  const float spacing = static_cast<float>(box.step) * voxel;
  // Samples that round to a node of the box lie within half a spacing of it.
  const Eigen::Vector3f half = Eigen::Vector3f::Constant(0.5f * spacing);
  const Eigen::Vector3f box_lo = box.origin.cast<float>() * voxel - half;
  const Eigen::Vector3f box_hi =
      (box.origin + box.step * (box.size - Eigen::Vector3i::Ones())).cast<float>() * voxel + half;
  const Eigen::Vector3f o = cloud.sensor_origin;
  const float step = 0.5f * spacing;
  tbb::parallel_for(std::size_t{0}, cloud.size(), [&](std::size_t i) {
    const Eigen::Vector3f ray = cloud.positions[i] - o;
    const float length = ray.norm();
    if (!(length > stop)) return;
    const Eigen::Vector3f d = ray / length;
    float t0 = 0.0f, t1 = 0.0f;
    if (!close_clip_segment(o, d, length - stop, box_lo, box_hi, t0, t1)) return;
    // Counted steps: `t += step` stops moving once t / step passes 2^24 (a sensor tens of
    // kilometres away at centimetre voxels). The clipped segment is at most the box's diagonal.
    const auto first = static_cast<std::int64_t>(std::ceil(t0 / step));
    const auto last = static_cast<std::int64_t>(std::floor(t1 / step));
    for (std::int64_t k = first; k <= last; ++k) {
      const Eigen::Vector3f q =
          ((o + (static_cast<float>(k) * step) * d) / voxel - box.origin.cast<float>()) /
          static_cast<float>(box.step);
      const Eigen::Vector3i c(static_cast<int>(std::lround(q.x())),
                              static_cast<int>(std::lround(q.y())),
                              static_cast<int>(std::lround(q.z())));
      if ((c.array() < 0).any() || (c.array() >= box.size.array()).any()) continue;
      marks[(static_cast<std::size_t>(c.z()) * box.size.y() + c.y()) * box.size.x() + c.x()].store(
          1, std::memory_order_relaxed);
    }
  });
  return marks;
}

// Everything a tile's solve reads: the data, the whole lattice's box, and the coarse solution
// that holds the faces of tiles inside the lattice (none when the lattice is one tile).
struct CloseProblem {
  const SparseGrid* grid = nullptr;
  const DistanceField* field = nullptr;
  const PointCloud* cloud = nullptr;
  const CloseConfig* config = nullptr;
  Eigen::Vector3i lo = Eigen::Vector3i::Zero();  // the lattice's first corner
  Eigen::Vector3i size = Eigen::Vector3i::Zero();
  float outside = 0.0f;  // the value held at the lattice's faces
  int margin = 1;        // nodes between the lattice's faces and the data's box
  /// A whole lattice for the gradient fill (or the automatic choice) not yet grown for it: the
  /// solve first asks for room past the data's box (TileResult::grow).
  bool reach = false;
  const DiffusionLattice* coarse = nullptr;
  int coarse_step = 1;
};

// Free nodes on one side of zero that no held node on that side reaches through free nodes
// of the same side (6-neighbours) flip to the other side: pockets of the fill, which would be
// extra components inside or beside the object (the double layer wobbles near the band's
// ends). Inside first (a pocket inside joins the outside next to it), then outside. The
// lattice's faces are held (a free node has all 6 neighbours). Serial breadth-first fills; the
// set reached does not depend on the order. O(nodes).
void close_drop_pockets(DiffusionLattice& l) {
  const Eigen::Vector3i n = l.size;
  const std::size_t nodes = l.node_count();
  std::vector<std::uint8_t> reached(nodes);
  std::vector<std::size_t> queue;
  for (const bool inside : {true, false}) {
    const auto side = [&](std::size_t i) { return (l.values[i] < 0.0f) == inside; };
    std::fill(reached.begin(), reached.end(), 0);
    queue.clear();
    for (std::size_t i = 0; i < nodes; ++i)
      if (l.fixed[i] && side(i)) {
        reached[i] = 1;
        queue.push_back(i);
      }
    const std::size_t row = static_cast<std::size_t>(n.x()), plane = row * n.y();
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const std::size_t i = queue[head];
      const auto visit = [&](std::size_t j) {
        if (reached[j] || l.fixed[j] || !side(j)) return;
        reached[j] = 1;
        queue.push_back(j);
      };
      if (!l.fixed[i]) {  // a free node is off the faces: all 6 neighbours exist
        assert(i % row != 0 && i % row + 1 != row && i / row % n.y() != 0 &&
               i / row % n.y() + 1 != static_cast<std::size_t>(n.y()) && i >= plane &&
               i + plane < nodes);
        visit(i - 1);
        visit(i + 1);
        visit(i - row);
        visit(i + row);
        visit(i - plane);
        visit(i + plane);
        continue;
      }
      const int x = static_cast<int>(i % row);
      const int y = static_cast<int>(i / row % static_cast<std::size_t>(n.y()));
      const int z = static_cast<int>(i / plane);
      if (x > 0) visit(i - 1);
      if (x + 1 < n.x()) visit(i + 1);
      if (y > 0) visit(l.index(x, y - 1, z));
      if (y + 1 < n.y()) visit(l.index(x, y + 1, z));
      if (z > 0) visit(l.index(x, y, z - 1));
      if (z + 1 < n.z()) visit(l.index(x, y, z + 1));
    }
    // A flipped node keeps its magnitude (at least a little), so that the surface around the
    // pocket's former place stays where its neighbours put it.
    for (std::size_t i = 0; i < nodes; ++i)
      if (!l.fixed[i] && !reached[i] && side(i))
        l.values[i] = inside ? std::max(std::abs(l.values[i]), 1e-6f)
                             : -std::max(std::abs(l.values[i]), 1e-6f);
  }
}

// The free nodes of `l` from the inside indicator the observed nodes' distances imply, spread
// as a double layer: w solves the Poisson equation whose source is the divergence of the
// indicator's jumps between observed neighbours (a discrete generalized winding number of the
// observed surface, the field Poisson surface reconstruction solves for), held at 0 on the
// other held nodes (the faces, lines of sight). Where the observed surface is open, the level
// of w through it spans the opening following the surface's turn, not harmonically between
// the band's few held values (which domed a box's unseen bottom deep into the box). Free nodes
// take alpha + beta w, fitted by least squares to the observed distances within a voxel of the
// surface (as Poisson reconstruction takes its iso-value from the samples); without a fit
// (beta >= 0) they are diffused instead. Sets `grow_below` to alpha / 2: a free node on the
// data's box with a value below it has w above half the level there, so the faces' zero is
// near enough to flatten the fill. Returns the levels of the solve.
int close_fill_by_indicator(DiffusionLattice& l, const std::vector<std::uint8_t>& observed,
                            float voxel, const DiffusionConfig& config, float& grow_below) {
  const std::size_t nodes = l.node_count();
  const Eigen::Vector3i n = l.size;
  std::vector<float> h(nodes, 0.0f);
  tbb::parallel_for(std::size_t{0}, nodes, [&](std::size_t i) {
    if (observed[i]) h[i] = std::clamp(0.5f - l.values[i] / (2.0f * voxel), 0.0f, 1.0f);
  });
  DiffusionLattice w;
  w.size = n;
  w.values.assign(nodes, 0.0f);
  w.fixed.assign(nodes, 0);
  w.source.assign(nodes, 0.0f);
  tbb::parallel_for(0, n.z(), [&](int z) {
    for (int y = 0; y < n.y(); ++y)
      for (int x = 0; x < n.x(); ++x) {
        const std::size_t i = l.index(x, y, z);
        if (l.fixed[i] && !observed[i]) {
          w.fixed[i] = 1;
          continue;
        }
        if (!observed[i]) continue;
        float s = 0.0f;
        const auto edge = [&](std::size_t j) {
          if (observed[j]) s += h[i] - h[j];
        };
        if (x > 0) edge(i - 1);
        if (x + 1 < n.x()) edge(i + 1);
        if (y > 0) edge(l.index(x, y - 1, z));
        if (y + 1 < n.y()) edge(l.index(x, y + 1, z));
        if (z > 0) edge(l.index(x, y, z - 1));
        if (z + 1 < n.z()) edge(l.index(x, y, z + 1));
        w.source[i] = s;
      }
  });
  const int levels = diffuse_free_nodes(w, config);
  // u = alpha + beta w by least squares over the observed nodes within a voxel of the surface
  // (sums per plane, added in plane order).
  std::vector<std::array<double, 5>> sums(static_cast<std::size_t>(n.z()), std::array<double, 5>{});
  tbb::parallel_for(0, n.z(), [&](int z) {
    std::array<double, 5>& s = sums[static_cast<std::size_t>(z)];
    for (std::size_t i = l.index(0, 0, z), end = i + static_cast<std::size_t>(n.x()) * n.y();
         i < end; ++i) {
      if (!observed[i] || std::abs(l.values[i]) > voxel) continue;
      const double wi = w.values[i], ui = l.values[i];
      s[0] += 1.0;
      s[1] += wi;
      s[2] += ui;
      s[3] += wi * wi;
      s[4] += wi * ui;
    }
  });
  double count = 0, sw = 0, su = 0, sww = 0, swu = 0;
  for (const auto& s : sums) {
    count += s[0];
    sw += s[1];
    su += s[2];
    sww += s[3];
    swu += s[4];
  }
  const double det = count * sww - sw * sw;
  const double beta = det > 0 ? (count * swu - sw * su) / det : 0.0;
  if (!(beta < 0.0)) return diffuse_free_nodes(l, config);
  const double alpha = (su - beta * sw) / count;
  tbb::parallel_for(std::size_t{0}, nodes, [&](std::size_t i) {
    if (!l.fixed[i]) l.values[i] = static_cast<float>(alpha + beta * w.values[i]);
  });
  close_drop_pockets(l);
  grow_below = static_cast<float>(0.5 * alpha);
  return levels;
}

// Observed nodes of `l` within `reach` steps (6-neighbours, through observed nodes) of the
// observed surface's rim: observed nodes within a voxel of the surface with a free neighbour
// across the gradient of the observed distances there (the step and the gradient at least 60
// degrees apart): where the surface goes on into unobserved space, not where its band ends
// beside it. Parallel over z-planes, one step at a time; O(nodes x reach).
std::vector<std::uint8_t> close_rim_band(const DiffusionLattice& l,
                                         const std::vector<std::uint8_t>& observed, float voxel,
                                         int reach) {
  const Eigen::Vector3i n = l.size;
  std::vector<std::uint8_t> band(l.node_count(), 0);
  const auto at = [&](const Eigen::Vector3i& q) { return l.index(q.x(), q.y(), q.z()); };
  const auto inside = [&](const Eigen::Vector3i& q) {
    return (q.array() >= 0).all() && (q.array() < n.array()).all();
  };
  tbb::parallel_for(0, n.z(), [&](int z) {
    for (int y = 0; y < n.y(); ++y)
      for (int x = 0; x < n.x(); ++x) {
        const Eigen::Vector3i q(x, y, z);
        const std::size_t i = at(q);
        if (!observed[i] || !(std::abs(l.values[i]) < voxel)) continue;
        Eigen::Vector3f g = Eigen::Vector3f::Zero();  // central or one-sided differences
        for (int k = 0; k < 3; ++k) {
          const Eigen::Vector3i e = Eigen::Vector3i::Unit(k);
          const bool minus = inside(q - e) && observed[at(q - e)];
          const bool plus = inside(q + e) && observed[at(q + e)];
          const float lo = minus ? l.values[at(q - e)] : l.values[i];
          const float hi = plus ? l.values[at(q + e)] : l.values[i];
          g[k] = minus && plus ? 0.5f * (hi - lo) : hi - lo;
        }
        const float norm = g.norm();
        if (!(norm > 0.3f * voxel)) continue;
        for (int k = 0; k < 3 && !band[i]; ++k)
          for (const int sign : {-1, 1}) {
            const Eigen::Vector3i j = q + sign * Eigen::Vector3i::Unit(k);
            if (inside(j) && !l.fixed[at(j)] && std::abs(g[k]) < 0.5f * norm) band[i] = 1;
          }
      }
  });
  std::vector<std::uint8_t> next(band.size());
  for (int step = 0; step < reach; ++step) {
    tbb::parallel_for(0, n.z(), [&](int z) {
      for (int y = 0; y < n.y(); ++y)
        for (int x = 0; x < n.x(); ++x) {
          const Eigen::Vector3i q(x, y, z);
          const std::size_t i = at(q);
          bool reached = band[i] != 0;
          for (int k = 0; k < 6 && !reached && observed[i]; ++k) {
            const Eigen::Vector3i j = q + (k % 2 == 0 ? -1 : 1) * Eigen::Vector3i::Unit(k / 2);
            reached = inside(j) && band[at(j)] != 0;
          }
          next[i] = reached ? 1 : 0;
        }
    });
    band.swap(next);
  }
  return band;
}

// What one tile gives back: its crossed cells, the values of their corners and of the grid's
// corners in the tile (sorted by key), and its counts. A skipped tile gives its grid corners
// the coarse solution's values in `fallback` instead.
struct TileResult {
  std::vector<VoxelKey> cells;
  std::vector<std::pair<VoxelKey, float>> values;
  std::vector<std::pair<VoxelKey, float>> fallback;
  CloseReport counts;
  /// Per side (-x, +x, -y, +y, -z, +z): a filled node on the data's box there (the margin
  /// from the lattice's face) is inside or near it, so the fill would go on past the lattice
  /// or feels the face (a solve of the whole lattice only).
  std::array<bool, 6> cut{};
  /// Per side: nodes to add past the lattice's face before the gradient fill solves (the
  /// observed surface turns to close beyond it; close_gradient_room()). Nonzero: not solved.
  std::array<int, 6> grow{};
};

// Holds the free nodes `marked` (by lattice index) outside at distance `stop`, in parallel over
// z-planes; returns how many of them the tile owns (`owned(x, y, z)`). O(nodes).
template <typename Marked, typename Owned>
std::size_t hold_outside(DiffusionLattice& l, float stop, const Marked& marked,
                         const Owned& owned) {
  const Eigen::Vector3i n = l.size;
  return tbb::parallel_reduce(
      tbb::blocked_range<int>(0, n.z()), std::size_t{0},
      [&](const tbb::blocked_range<int>& r, std::size_t count) {
        for (int z = r.begin(); z != r.end(); ++z)
          for (int y = 0; y < n.y(); ++y)
            for (int x = 0; x < n.x(); ++x) {
              const std::size_t i = l.index(x, y, z);
              if (!marked(i) || l.fixed[i]) continue;
              l.fixed[i] = 1;
              l.values[i] = stop;
              count += owned(x, y, z) ? 1 : 0;
            }
        return count;
      },
      std::plus<>());
}

// through_line_nodes() on every second node of the lattice (an eighth of the nodes: coarse
// node c is node min(2 c, size - 1), with its side), brought back to the lattice: a node
// without data is on a through line when all the coarse nodes around it (the 1 to 8 at
// floor(q / 2) and ceil(q / 2) per axis) are. Tunnels narrower than about two coarse spacings
// (four voxels) are not found. Parallel over planes; O(230 x nodes / 8).
std::vector<std::uint8_t> close_through_nodes(const Eigen::Vector3i& size,
                                              const std::vector<std::uint8_t>& side) {
  const Eigen::Vector3i last = size - Eigen::Vector3i::Ones();
  const Eigen::Vector3i coarse = (size.array() / 2 + 1).matrix();
  const auto fine_index = [&](const Eigen::Vector3i& q) {
    return (static_cast<std::size_t>(q.z()) * static_cast<std::size_t>(size.y()) +
            static_cast<std::size_t>(q.y())) *
               static_cast<std::size_t>(size.x()) +
           static_cast<std::size_t>(q.x());
  };
  const auto coarse_index = [&](const Eigen::Vector3i& c) {
    return (static_cast<std::size_t>(c.z()) * static_cast<std::size_t>(coarse.y()) +
            static_cast<std::size_t>(c.y())) *
               static_cast<std::size_t>(coarse.x()) +
           static_cast<std::size_t>(c.x());
  };
  std::vector<std::uint8_t> coarse_side(static_cast<std::size_t>(coarse.prod()));
  tbb::parallel_for(0, coarse.z(), [&](int z) {
    for (int y = 0; y < coarse.y(); ++y)
      for (int x = 0; x < coarse.x(); ++x) {
        const Eigen::Vector3i c(x, y, z);
        coarse_side[coarse_index(c)] = side[fine_index((2 * c).cwiseMin(last))];
      }
  });
  const std::vector<std::uint8_t> coarse_through = through_line_nodes(coarse, coarse_side);
  std::vector<std::uint8_t> through(side.size(), 0);
  tbb::parallel_for(0, size.z(), [&](int z) {
    for (int y = 0; y < size.y(); ++y)
      for (int x = 0; x < size.x(); ++x) {
        const Eigen::Vector3i q(x, y, z);
        if (side[fine_index(q)] != 0) continue;
        const Eigen::Vector3i lo = q / 2, hi = ((q.array() + 1) / 2)
                                                   .matrix()
                                                   .cwiseMin(coarse - Eigen::Vector3i::Ones());
        bool all = true;
        for (int cz = lo.z(); cz <= hi.z() && all; ++cz)
          for (int cy = lo.y(); cy <= hi.y() && all; ++cy)
            for (int cx = lo.x(); cx <= hi.x() && all; ++cx)
              all = coarse_through[coarse_index({cx, cy, cz})] != 0;
        through[fine_index(q)] = all ? 1 : 0;
      }
  });
  return through;
}

// The observed nodes within this many nodes of the data's box on a side fit the reach.
constexpr int kGradientReachWindow = 8;

// Per side of `l` (a whole lattice with `margin` nodes between its faces and the data's box):
// the nodes the gradient fill needs past the face (`fraction` of the reach, rounded up; 0 where
// the surface does not turn within the data's length on that axis). O(nodes).
std::array<int, 6> close_gradient_room(const DiffusionLattice& l,
                                       const std::vector<std::uint8_t>& observed, float voxel,
                                       int margin, float fraction) {
  const std::array<float, 6> reach =
      gradient_fill_reach(l, observed, voxel, margin, kGradientReachWindow);
  std::array<int, 6> room{};
  for (std::size_t side = 0; side < 6; ++side) {
    const int length = l.size[static_cast<int>(side / 2)] - 2 * margin;
    if (reach[side] > 0.0f && reach[side] <= static_cast<float>(length))
      room[side] = static_cast<int>(std::ceil(std::max(0.0f, fraction) * reach[side]));
  }
  return room;
}

// Sets the values of the nodes on the faces of `l` (held) to `value`. Parallel over planes.
void close_set_faces(DiffusionLattice& l, float value) {
  const Eigen::Vector3i n = l.size;
  tbb::parallel_for(0, n.z(), [&](int z) {
    for (int y = 0; y < n.y(); ++y)
      for (int x = 0; x < n.x(); ++x)
        if (x == 0 || y == 0 || z == 0 || x + 1 == n.x() || y + 1 == n.y() || z + 1 == n.z())
          l.values[l.index(x, y, z)] = value;
  });
}

// The automatic fill keeps the gradient fill unless another fill predicts the held-out rim
// below this fraction of the gradient fill's error. The rim error does not rank the fills by
// their filled error: on the 12 scans of tests/graph/test_scanned_objects.cpp the gradient fill
// has the lowest filled error on all 12, but the highest rim error on 8 (the flat-bottomed
// shapes: at a sharp rim a fill that stays near its held values predicts better), where the
// lower of the others' rim errors was 0.54-0.75 of its own (diffusion's filled error 1.4-13x
// the gradient fill's, the indicator's 1.5-3.9x); choosing the lowest rim error gave a mean
// filled error of 11.3e-3 against the gradient fill's 5.6e-3. The sign of the prediction, the
// nodes within a voxel of the surface only, or a band of 6 steps ranked them no better (8 of
// 12 wrong each).
constexpr float kAutomaticMargin = 0.5f;

// Self-validation of a whole lattice's three fills: the observed nodes near the observed
// surface's rim (close_rim_band) are freed, each fill (the gradient's and the indicator's with
// the `through` nodes held outside at `stop`) predicts them from the rest, and each fill's
// error is the mean over them of |prediction - observed distance| in voxels, clamped at 2 a
// node (a far miss counts as a miss). Diffusion and the indicator take an eighth of the fill's
// sweeps per level (they rank the fills, the final fill converges); the gradient fill, whose
// solves already take a quarter and an eighth, the fill's own. Records the errors and the
// held-out count in `counts`; returns the gradient fill unless diffusion or the indicator has
// an error below kAutomaticMargin of its own (then the lower, diffusion among equals). No
// held-out node: the gradient fill (the default). The
// gradient fill's faces are held at `gradient_faces` (CloseConfig::gradient_face_voxels).
CloseFill close_choose_fill(const DiffusionLattice& l, const std::vector<std::uint8_t>& observed,
                            const std::vector<std::uint8_t>& through, float voxel, float stop,
                            float gradient_faces, const CloseConfig& config, CloseReport& counts) {
  const std::vector<std::uint8_t> held_out =
      close_rim_band(l, observed, voxel, std::max(0, config.validation_band));
  counts.held_out = static_cast<std::size_t>(std::count(held_out.begin(), held_out.end(), 1));
  if (counts.held_out == 0) return CloseFill::gradient;
  DiffusionLattice diffused = l;
  std::vector<std::uint8_t> kept = observed;
  for (std::size_t i = 0; i < held_out.size(); ++i)
    if (held_out[i]) {
      diffused.fixed[i] = 0;
      diffused.values[i] = 0.0f;
      kept[i] = 0;
    }
  DiffusionLattice indicator = diffused;
  hold_outside(
      indicator, stop, [&](std::size_t i) { return through[i] != 0; },
      [](int, int, int) { return false; });
  DiffusionLattice gradient = indicator;
  DiffusionConfig quick = config.diffusion;
  quick.sweeps_per_level = std::max(1, quick.sweeps_per_level / 8);
  diffuse_free_nodes(diffused, quick);
  float unused = 0.0f;
  close_fill_by_indicator(indicator, kept, voxel, quick, unused);
  close_set_faces(gradient, gradient_faces);
  gradient_fill(gradient, kept, voxel, config.diffusion);
  close_drop_pockets(gradient);
  const auto error = [&](const DiffusionLattice& fill) {
    std::vector<double> per_plane(static_cast<std::size_t>(l.size.z()), 0.0);
    tbb::parallel_for(0, l.size.z(), [&](int z) {
      for (int y = 0; y < l.size.y(); ++y)
        for (int x = 0; x < l.size.x(); ++x) {
          const std::size_t i = l.index(x, y, z);
          if (held_out[i])
            per_plane[static_cast<std::size_t>(z)] +=
                std::min(std::abs(fill.values[i] - l.values[i]) / voxel, 2.0f);
        }
    });
    double sum = 0.0;
    for (const double v : per_plane) sum += v;
    return static_cast<float>(sum / static_cast<double>(counts.held_out));
  };
  counts.held_out_error_gradient = error(gradient);
  counts.held_out_error_diffusion = error(diffused);
  counts.held_out_error_indicator = error(indicator);
  // The gradient fill unless another's error is below kAutomaticMargin of its own (then the
  // lower of the two others').
  const float bar = kAutomaticMargin * counts.held_out_error_gradient;
  if (counts.held_out_error_diffusion < bar &&
      counts.held_out_error_diffusion <= counts.held_out_error_indicator)
    return CloseFill::diffusion;
  if (counts.held_out_error_indicator < bar) return CloseFill::indicator;
  return CloseFill::gradient;
}

// Solves the tile of lattice nodes [a, b] (inclusive, relative to the lattice): held nodes are
// the lattice's faces, the tile's other faces (at the coarse solution), the data's corners
// (`corners`: indices into the grid, those in the tile) and the seen-empty nodes; free ones are
// diffused. Counts nodes of [a, b) only (b too on the lattice's last face), so that tiles
// sharing a face count it once.
TileResult close_solve_tile(const CloseProblem& p, const Eigen::Vector3i& a,
                            const Eigen::Vector3i& b, const std::vector<std::uint32_t>& corners) {
  TileResult out;
  DiffusionLattice l;
  l.size = b - a + Eigen::Vector3i::Ones();
  l.values.assign(l.node_count(), 0.0f);
  l.fixed.assign(l.node_count(), 0);
  const Eigen::Vector3i n = l.size;
  const auto owned = [&](int x, int y, int z) {
    const Eigen::Vector3i q = a + Eigen::Vector3i(x, y, z);
    for (int k = 0; k < 3; ++k)
      if (q[k] == b[k] && b[k] + 1 != p.size[k]) return false;
    return true;
  };
  // Faces: the lattice's are outside, a tile's inner ones take the coarse solution.
  tbb::parallel_for(0, n.z(), [&](int z) {
    for (int y = 0; y < n.y(); ++y)
      for (int x = 0; x < n.x(); ++x) {
        if (x > 0 && y > 0 && z > 0 && x + 1 < n.x() && y + 1 < n.y() && z + 1 < n.z()) continue;
        const Eigen::Vector3i q = a + Eigen::Vector3i(x, y, z);
        const bool lattice_face = (q.array() == 0).any() || (q.array() + 1 == p.size.array()).any();
        const std::size_t i = l.index(x, y, z);
        l.fixed[i] = 1;
        l.values[i] =
            lattice_face || p.coarse == nullptr
                ? p.outside
                : interpolate_coarse(*p.coarse, Eigen::Vector3i::Constant(p.coarse_step), q);
      }
  });
  const auto node_of = [&](VoxelKey key) {
    const Eigen::Vector3i c = unpack_key(key) - p.lo - a;
    return l.index(c.x(), c.y(), c.z());
  };
  // The data's corners (each a distinct node: any order writes the same).
  std::vector<std::uint8_t> observed(l.node_count(), 0);
  out.counts.observed = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, corners.size(), 4096), std::size_t{0},
      [&](const tbb::blocked_range<std::size_t>& r, std::size_t count) {
        for (std::size_t k = r.begin(); k != r.end(); ++k) {
          const std::uint32_t c = corners[k];
          if (!p.field->valid[c]) continue;
          const Eigen::Vector3i q = unpack_key(p.grid->corners[c]) - p.lo - a;
          const std::size_t i = l.index(q.x(), q.y(), q.z());
          l.fixed[i] = 1;
          observed[i] = 1;
          l.values[i] = p.field->values[c];
          count += owned(q.x(), q.y(), q.z()) ? 1 : 0;
        }
        return count;
      },
      std::plus<>());
  if (p.cloud->has_sensor_origin && !p.cloud->empty()) {  // data wins over a grazing sight line
    const float voxel = p.grid->voxel_size;
    const float stop = p.config->free_space_stop_voxels * voxel;
    const auto marks = close_sight_marks(*p.cloud, NodeBox{p.lo + a, 1, n}, voxel, stop);
    out.counts.seen_empty = hold_outside(
        l, stop, [&](std::size_t i) { return marks[i].load(std::memory_order_relaxed) != 0; },
        owned);
  }
  // A whole lattice of a cloud's distances: config.fill (by default the gradient fill); a tile:
  // diffusion between its faces, which hold the coarse solution (the double layer and the
  // gradient's potential need the whole surface). A fused map (no points) is diffused too: its
  // observed voxels fill the truncation band on both sides, and the double layer of its ragged
  // band's ends left small extra shells (CliClose.FusedAndMergedDepthSequencesCloseWatertight).
  // The gradient fill grows the lattice only before it solves, where the observed surface turns
  // to close past the data's box (close_gradient_room), never after: a fill reaching the data's
  // box there is the surface carrying on as it was heading, and a grown lattice let it carry on
  // to the new faces (a box's unseen bottom 20 voxels deep).
  float grow_below = 0.0f;  // a free node on the data's box below this: the lattice is too small
  CloseFill method =
      p.coarse == nullptr && !p.cloud->empty() ? p.config->fill : CloseFill::diffusion;
  if (p.reach && (method == CloseFill::gradient || method == CloseFill::automatic)) {
    out.grow = close_gradient_room(l, observed, p.grid->voxel_size, p.margin,
                                   p.config->gradient_reach_fraction);
    if (std::any_of(out.grow.begin(), out.grow.end(), [](int g) { return g > 0; })) return out;
  }
  // A whole lattice's faces for the gradient fill (the lattice is one tile: all its faces are
  // the lattice's).
  const float gradient_faces = p.outside + p.config->gradient_face_voxels * p.grid->voxel_size;
  if (method != CloseFill::diffusion) {
    // Lines through observed tunnels are held outside like lines of sight: the double layer
    // of an open tunnel's upper part would cap it where its walls were unseen, and so would the
    // gradient fill (the top's field carried down past the tunnel's unseen lower walls closed
    // the box with a hole's hole at the bottom).
    const float stop = p.config->free_space_stop_voxels * p.grid->voxel_size;
    std::vector<std::uint8_t> side(l.node_count(), 0);
    tbb::parallel_for(std::size_t{0}, side.size(), [&](std::size_t i) {
      if (observed[i]) side[i] = l.values[i] > 0.0f ? 1 : 2;
    });
    const std::vector<std::uint8_t> through = close_through_nodes(n, side);
    if (method == CloseFill::automatic)
      method = close_choose_fill(l, observed, through, p.grid->voxel_size, stop, gradient_faces,
                                 *p.config, out.counts);
    if (method != CloseFill::diffusion)
      out.counts.through = hold_outside(
          l, stop, [&](std::size_t i) { return through[i] != 0; }, owned);
  }
  const bool indicator = method == CloseFill::indicator;
  const bool gradient = method == CloseFill::gradient;
  out.counts.indicator = indicator;
  out.counts.fill = method;
  if (indicator)
    out.counts.levels =
        close_fill_by_indicator(l, observed, p.grid->voxel_size, p.config->diffusion, grow_below);
  else if (gradient) {
    close_set_faces(l, gradient_faces);
    out.counts.levels = gradient_fill(l, observed, p.grid->voxel_size, p.config->diffusion);
    close_drop_pockets(l);
  } else {
    out.counts.levels = diffuse_free_nodes(l, p.config->diffusion);
  }
  // Filled nodes, and the sides where one next to the lattice's face is inside (per plane,
  // joined in plane order).
  std::vector<std::size_t> filled(static_cast<std::size_t>(n.z()), 0);
  std::vector<std::array<bool, 6>> cut(static_cast<std::size_t>(n.z()), std::array<bool, 6>{});
  tbb::parallel_for(0, n.z(), [&](int z) {
    for (int y = 0; y < n.y(); ++y)
      for (int x = 0; x < n.x(); ++x) {
        const std::size_t i = l.index(x, y, z);
        if (l.fixed[i]) continue;
        filled[static_cast<std::size_t>(z)] += owned(x, y, z) ? 1 : 0;
        if (!(l.values[i] < grow_below) || p.coarse != nullptr || gradient) continue;
        const Eigen::Vector3i q(x, y, z);
        for (int k = 0; k < 3; ++k) {
          if (q[k] == p.margin)
            cut[static_cast<std::size_t>(z)][static_cast<std::size_t>(2 * k)] = true;
          if (q[k] + 1 + p.margin == n[k])
            cut[static_cast<std::size_t>(z)][static_cast<std::size_t>(2 * k + 1)] = true;
        }
      }
  });
  for (std::size_t z = 0; z < filled.size(); ++z) {
    out.counts.filled += filled[z];
    for (std::size_t k = 0; k < 6; ++k) out.cut[k] = out.cut[k] || cut[z][k];
  }

  // Crossed cells with all corners in the tile, that the grid lacks; their corners' values.
  const std::vector<VoxelKey>& existing = p.grid->cells;
  std::vector<std::vector<VoxelKey>> per_plane(static_cast<std::size_t>(n.z() - 1));
  tbb::parallel_for(0, n.z() - 1, [&](int z) {
    std::vector<VoxelKey>& plane = per_plane[static_cast<std::size_t>(z)];
    for (int y = 0; y + 1 < n.y(); ++y)
      for (int x = 0; x + 1 < n.x(); ++x) {
        int inside = 0;
        for (int c = 0; c < 8; ++c)
          inside += l.values[l.index(x + (c & 1), y + ((c >> 1) & 1), z + ((c >> 2) & 1))] < 0.0f;
        if (inside == 0 || inside == 8) continue;
        const VoxelKey key = pack_key(p.lo + a + Eigen::Vector3i(x, y, z));
        if (!std::binary_search(existing.begin(), existing.end(), key)) plane.push_back(key);
      }
  });
  for (const auto& plane : per_plane) out.cells.insert(out.cells.end(), plane.begin(), plane.end());
  std::vector<VoxelKey> keys(out.cells.size() * 8 + corners.size());
  tbb::parallel_for(std::size_t{0}, out.cells.size(), [&](std::size_t i) {
    const Eigen::Vector3i c = unpack_key(out.cells[i]);
    for (int k = 0; k < 8; ++k)
      keys[8 * i + static_cast<std::size_t>(k)] =
          pack_key(c + Eigen::Vector3i(k & 1, (k >> 1) & 1, (k >> 2) & 1));
  });
  tbb::parallel_for(std::size_t{0}, corners.size(), [&](std::size_t i) {
    keys[8 * out.cells.size() + i] = p.grid->corners[corners[i]];
  });
  tbb::parallel_sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  out.values.resize(keys.size());
  tbb::parallel_for(std::size_t{0}, keys.size(), [&](std::size_t i) {
    out.values[i] = {keys[i], l.values[node_of(keys[i])]};
  });
  return out;
}

// The coarse lattice of a large problem: node i at lattice node step x i; held where a data
// corner rounds to it (the mean of their values), on the lattice's faces, and on lines of sight
// (stopping a coarse spacing earlier). Solved.
DiffusionLattice close_coarse_solution(const CloseProblem& p, int step, int& levels) {
  DiffusionLattice coarse;
  coarse.size = (p.size.array() - 1 + step - 1) / step + 1;
  coarse.values.assign(coarse.node_count(), 0.0f);
  coarse.fixed.assign(coarse.node_count(), 0);
  std::vector<std::uint32_t> count(coarse.node_count(), 0);
  const Eigen::Vector3i n = coarse.size;
  // The grid's corners are sorted by key, z first: those of coarse plane z (rounding to it) are
  // one range, and each plane sums its own nodes' corners in the corners' order (the serial
  // loop's sums, whatever the thread count).
  const std::vector<VoxelKey>& keys = p.grid->corners;
  const auto first_at_z = [&](int z) {  // the first corner whose lattice z is at least z
    return static_cast<std::size_t>(std::lower_bound(keys.begin(), keys.end(), z,
                                                     [&](VoxelKey k, int value) {
                                                       return unpack_key(k).z() - p.lo.z() < value;
                                                     }) -
                                    keys.begin());
  };
  tbb::parallel_for(0, n.z(), [&](int cz) {
    // Coarse plane cz gathers lattice planes [cz step - step / 2, cz step + step - step / 2),
    // the last one everything above.
    const std::size_t begin = cz == 0 ? 0 : first_at_z(cz * step - step / 2);
    const std::size_t end = cz + 1 == n.z() ? keys.size() : first_at_z((cz + 1) * step - step / 2);
    for (std::size_t c = begin; c < end; ++c) {
      if (!p.field->valid[c]) continue;
      const Eigen::Vector3i q = unpack_key(keys[c]) - p.lo;
      const Eigen::Vector3i r =
          ((q.array() + step / 2) / step).matrix().cwiseMin(n - Eigen::Vector3i::Ones());
      const std::size_t i = coarse.index(r.x(), r.y(), r.z());
      coarse.values[i] += p.field->values[c];
      ++count[i];
    }
    for (int y = 0; y < n.y(); ++y)
      for (int x = 0; x < n.x(); ++x) {
        const std::size_t i = coarse.index(x, y, cz);
        if (count[i] == 0) continue;
        coarse.fixed[i] = 1;
        coarse.values[i] /= static_cast<float>(count[i]);
      }
  });
  for (int z = 0; z < n.z(); ++z)
    for (int y = 0; y < n.y(); ++y)
      for (int x = 0; x < n.x(); ++x) {
        if (x > 0 && y > 0 && z > 0 && x + 1 < n.x() && y + 1 < n.y() && z + 1 < n.z()) continue;
        coarse.fixed[coarse.index(x, y, z)] = 1;
        coarse.values[coarse.index(x, y, z)] = p.outside;
      }
  if (p.cloud->has_sensor_origin && !p.cloud->empty()) {
    const float voxel = p.grid->voxel_size;
    const float stop = (p.config->free_space_stop_voxels + static_cast<float>(step)) * voxel;
    const auto marks = close_sight_marks(*p.cloud, NodeBox{p.lo, step, n}, voxel, stop);
    for (std::size_t i = 0; i < coarse.node_count(); ++i)
      if (marks[i].load(std::memory_order_relaxed) && !coarse.fixed[i]) {
        coarse.fixed[i] = 1;
        coarse.values[i] = stop;
      }
  }
  levels = diffuse_free_nodes(coarse, p.config->diffusion);
  return coarse;
}

// `grid` with the sorted cells `added` (none of them the grid's): the cells merged, the corners
// of both (sorted, unique; a corner of the grid that none of its cells uses is dropped) and
// each cell's corner indices (the grid's renumbered, the added cells' looked up). Linear merges
// plus O(added log corners); the same grid as building it from all the cells at once.
SparseGrid close_grid_with_cells(const SparseGrid& grid, const std::vector<VoxelKey>& added) {
  SparseGrid out;
  out.voxel_size = grid.voxel_size;
  std::vector<VoxelKey> added_corners(added.size() * 8);
  tbb::parallel_for(std::size_t{0}, added.size(), [&](std::size_t i) {
    const Eigen::Vector3i c = unpack_key(added[i]);
    for (int k = 0; k < 8; ++k)
      added_corners[i * 8 + static_cast<std::size_t>(k)] =
          pack_key(c + Eigen::Vector3i(k & 1, (k >> 1) & 1, (k >> 2) & 1));
  });
  tbb::parallel_sort(added_corners.begin(), added_corners.end());
  added_corners.erase(std::unique(added_corners.begin(), added_corners.end()), added_corners.end());
  std::vector<std::uint8_t> used(grid.corners.size(), 0);
  for (const auto& cell : grid.cell_corners)
    for (const std::uint32_t c : cell) used[c] = 1;
  // The corners merged; renumbered[c]: the new index of the grid's corner c.
  std::vector<std::uint32_t> renumbered(grid.corners.size(), 0);
  out.corners.reserve(grid.corners.size() + added_corners.size());
  std::size_t j = 0;
  for (std::size_t c = 0; c < grid.corners.size(); ++c) {
    if (!used[c]) continue;
    for (; j < added_corners.size() && added_corners[j] < grid.corners[c]; ++j)
      out.corners.push_back(added_corners[j]);
    if (j < added_corners.size() && added_corners[j] == grid.corners[c]) ++j;
    renumbered[c] = static_cast<std::uint32_t>(out.corners.size());
    out.corners.push_back(grid.corners[c]);
  }
  out.corners.insert(out.corners.end(), added_corners.begin() + static_cast<std::ptrdiff_t>(j),
                     added_corners.end());
  // The cells merged, each with its corners.
  out.cells.resize(grid.cells.size() + added.size());
  out.cell_corners.resize(out.cells.size());
  std::size_t g = 0, k = 0;
  for (std::size_t i = 0; i < out.cells.size(); ++i) {
    if (k == added.size() || (g < grid.cells.size() && grid.cells[g] < added[k])) {
      out.cells[i] = grid.cells[g];
      for (std::size_t c = 0; c < 8; ++c)
        out.cell_corners[i][c] = renumbered[grid.cell_corners[g][c]];
      ++g;
    } else {
      out.cells[i] = added[k++];
      out.cell_corners[i][0] = UINT32_MAX;  // looked up below
    }
  }
  tbb::parallel_for(std::size_t{0}, out.cells.size(), [&](std::size_t i) {
    if (out.cell_corners[i][0] != UINT32_MAX) return;
    const Eigen::Vector3i c = unpack_key(out.cells[i]);
    for (int q = 0; q < 8; ++q)
      out.cell_corners[i][static_cast<std::size_t>(q)] =
          out.find_corner(c + Eigen::Vector3i(q & 1, (q >> 1) & 1, (q >> 2) & 1));
  });
  return out;
}

// The tiles of side `cells` along one axis of `nodes` nodes: tile t spans nodes
// [t cells, min((t + 1) cells, nodes - 1)]; neighbours share a face.
int close_tile_count(int nodes, int cells) { return std::max(1, (nodes - 2) / cells + 1); }

}  // namespace

const char* close_fill_name(CloseFill fill) {
  switch (fill) {
    case CloseFill::automatic:
      return "automatic";
    case CloseFill::diffusion:
      return "diffusion";
    case CloseFill::indicator:
      return "indicator";
    case CloseFill::gradient:
      return "gradient";
  }
  return "diffusion";
}

ClosedDistance close_distance_field(const SparseGrid& grid, const DistanceField& field,
                                    const PointCloud& cloud, const CloseConfig& config,
                                    CloseReport* report) {
  CloseReport r;
  ClosedDistance out;
  const float voxel = grid.voxel_size;
  if (grid.corners.empty() || field.valid_count() == 0) {
    out.grid = grid;
    out.distance = field;
    if (report != nullptr) *report = r;
    return out;
  }
  // 1. The lattice: the grid's corners grown by the margin (their bounds: a min / max
  // reduction, the same whatever the order of its parts).
  using Bounds = std::pair<Eigen::Vector3i, Eigen::Vector3i>;
  const Eigen::Vector3i first = unpack_key(grid.corners.front());
  const Bounds bounds = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, grid.corners.size(), 1 << 14), Bounds{first, first},
      [&](const tbb::blocked_range<std::size_t>& range, Bounds b) {
        for (std::size_t c = range.begin(); c != range.end(); ++c) {
          const Eigen::Vector3i q = unpack_key(grid.corners[c]);
          b.first = b.first.cwiseMin(q);
          b.second = b.second.cwiseMax(q);
        }
        return b;
      },
      [](const Bounds& x, const Bounds& y) {
        return Bounds{x.first.cwiseMin(y.first), x.second.cwiseMax(y.second)};
      });
  Eigen::Vector3i lo = bounds.first, hi = bounds.second;
  const int margin = std::max(1, static_cast<int>(std::ceil(config.margin_voxels)));
  lo.array() -= margin;
  hi.array() += margin;
  CloseProblem p;
  p.grid = &grid;
  p.field = &field;
  p.cloud = &cloud;
  // The automatic fill chooses once, on the first lattice: a grown lattice keeps that fill (the
  // gradient fill chosen again on a lattice grown for another fill ran on to the new faces: the
  // box scan's filled error 91e-3 instead of 13e-3).
  CloseConfig round_config = config;
  CloseReport choice;
  p.config = &round_config;
  p.lo = lo;
  p.size = hi - lo + Eigen::Vector3i::Ones();
  p.outside = static_cast<float>(margin) * voxel;
  p.margin = margin;
  p.reach = config.fill == CloseFill::gradient || config.fill == CloseFill::automatic;
  r.lattice = p.size;
  const auto nodes_of = [](const Eigen::Vector3i& s) {
    return static_cast<double>(s.x()) * s.y() * s.z();
  };
  const double limit = static_cast<double>(std::max<std::size_t>(config.max_dense_corners, 64));

  std::vector<TileResult> results;
  DiffusionLattice coarse;
  for (int round = 0;; ++round) {
    // 2. A large lattice: the coarse solution over the whole box, and tiles of tile_cells.
    int cells = std::max(p.size.maxCoeff(), 2);
    if (nodes_of(p.size) > limit) {
      int step = 2;
      while (nodes_of(((p.size.array() - 2 + step) / step + 1).matrix()) > limit) step *= 2;
      p.coarse_step = step;
      coarse = close_coarse_solution(p, step, r.levels);
      p.coarse = &coarse;
      cells = std::max(2, config.tile_cells);
    }
    r.coarse_step = p.coarse_step;
    const Eigen::Vector3i tiles(close_tile_count(p.size.x(), cells),
                                close_tile_count(p.size.y(), cells),
                                close_tile_count(p.size.z(), cells));
    // The grid's corners per tile (a corner on a shared face goes to both tiles).
    const std::size_t tile_count = static_cast<std::size_t>(tiles.x()) * tiles.y() * tiles.z();
    const auto tile_index = [&](const Eigen::Vector3i& t) {
      return (static_cast<std::size_t>(t.z()) * tiles.y() + t.y()) * tiles.x() + t.x();
    };
    // (tile, corner) pairs per fixed block of corners, joined in block order and sorted (the
    // pairs are distinct: any sort gives one order), then cut into each tile's range.
    constexpr std::size_t kBlock = std::size_t{1} << 16;
    const std::size_t blocks = (grid.corners.size() + kBlock - 1) / kBlock;
    std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> per_block(blocks);
    tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t k) {
      const auto end = static_cast<std::uint32_t>(std::min(grid.corners.size(), (k + 1) * kBlock));
      for (auto c = static_cast<std::uint32_t>(k * kBlock); c < end; ++c) {
        const Eigen::Vector3i q = unpack_key(grid.corners[c]) - lo;
        Eigen::Vector3i from, to;
        for (int a = 0; a < 3; ++a) {
          to[a] = std::min(q[a] / cells, tiles[a] - 1);
          from[a] = q[a] % cells == 0 && q[a] > 0 ? q[a] / cells - 1 : to[a];
        }
        for (int z = from.z(); z <= to.z(); ++z)
          for (int y = from.y(); y <= to.y(); ++y)
            for (int x = from.x(); x <= to.x(); ++x)
              per_block[k].emplace_back(static_cast<std::uint32_t>(tile_index({x, y, z})), c);
      }
    });
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    for (auto& b : per_block) {
      pairs.insert(pairs.end(), b.begin(), b.end());
      b = {};
    }
    tbb::parallel_sort(pairs.begin(), pairs.end());
    std::vector<std::vector<std::uint32_t>> tile_corners(tile_count);
    tbb::parallel_for(std::size_t{0}, tile_count, [&](std::size_t t) {
      const auto tile = static_cast<std::uint32_t>(t);
      const auto begin = std::lower_bound(pairs.begin(), pairs.end(), std::make_pair(tile, 0u));
      const auto end = std::lower_bound(begin, pairs.end(), std::make_pair(tile + 1, 0u));
      tile_corners[t].reserve(static_cast<std::size_t>(end - begin));
      for (auto at = begin; at != end; ++at) tile_corners[t].push_back(at->second);
    });

    // 3. Each tile: skipped when it holds no data and the coarse solution is outside all over it
    // (its fine solution, bounded by its faces' values, is then outside too), else solved.
    results.assign(tile_count, TileResult{});
    std::atomic<std::size_t> solved{0};
    tbb::parallel_for(std::size_t{0}, tile_count, [&](std::size_t t) {
      const Eigen::Vector3i ti(
          static_cast<int>(t % static_cast<std::size_t>(tiles.x())),
          static_cast<int>(t / tiles.x() % static_cast<std::size_t>(tiles.y())),
          static_cast<int>(t / (static_cast<std::size_t>(tiles.x()) * tiles.y())));
      const Eigen::Vector3i a = ti * cells;
      const Eigen::Vector3i b =
          (a.array() + cells).matrix().cwiseMin(p.size - Eigen::Vector3i::Ones());
      const std::vector<std::uint32_t>& corners = tile_corners[t];
      if (p.coarse != nullptr && std::none_of(corners.begin(), corners.end(),
                                              [&](std::uint32_t c) { return field.valid[c]; })) {
        bool outside = true;
        const Eigen::Vector3i c0 = a / p.coarse_step;
        const Eigen::Vector3i c1 = ((b.array() + p.coarse_step - 1) / p.coarse_step)
                                       .matrix()
                                       .cwiseMin(coarse.size - Eigen::Vector3i::Ones());
        for (int z = c0.z(); z <= c1.z() && outside; ++z)
          for (int y = c0.y(); y <= c1.y() && outside; ++y)
            for (int x = c0.x(); x <= c1.x() && outside; ++x)
              outside = coarse.values[coarse.index(x, y, z)] > 0.0f;
        if (outside) {
          for (std::uint32_t c : corners)  // the grid's corners without data, if any
            results[t].fallback.emplace_back(
                grid.corners[c],
                interpolate_coarse(coarse, Eigen::Vector3i::Constant(p.coarse_step),
                                   unpack_key(grid.corners[c]) - lo));
          return;
        }
      }
      results[t] = close_solve_tile(p, a, b, corners);
      solved.fetch_add(1, std::memory_order_relaxed);
    });
    r.tiles = solved.load();
    // A whole lattice whose fill reaches one of its faces: that side grows (a quarter of the
    // lattice's extent there, at least the margin) and the lattice is solved again, at most
    // twice and while it stays under the dense limit.
    if (p.coarse != nullptr || round == 2) break;
    // The gradient fill's room (asked once, before it solved): those sides grow (unless that
    // passes the dense limit) and it solves; not one of the two growths below.
    const std::array<int, 6> room = results.front().grow;
    if (std::exchange(p.reach, false) &&
        std::any_of(room.begin(), room.end(), [](int g) { return g > 0; })) {
      const Eigen::Vector3i room_lo(room[0], room[2], room[4]), room_hi(room[1], room[3], room[5]);
      if (nodes_of(p.size + room_lo + room_hi) <= limit) {
        lo -= room_lo;
        p.lo = lo;
        p.size += room_lo + room_hi;
        r.lattice = p.size;
        r.grown = true;
      }
      --round;
      continue;
    }
    Eigen::Vector3i grow_lo = Eigen::Vector3i::Zero(), grow_hi = Eigen::Vector3i::Zero();
    for (int k = 0; k < 3; ++k) {
      const int g = std::max(margin, p.size[k] / 4);
      if (results.front().cut[static_cast<std::size_t>(2 * k)]) grow_lo[k] = g;
      if (results.front().cut[static_cast<std::size_t>(2 * k + 1)]) grow_hi[k] = g;
    }
    if ((grow_lo + grow_hi).maxCoeff() == 0 || nodes_of(p.size + grow_lo + grow_hi) > limit) break;
    if (round_config.fill == CloseFill::automatic) {
      choice = results.front().counts;
      round_config.fill = choice.fill;
    }
    lo -= grow_lo;
    p.lo = lo;
    p.size += grow_lo + grow_hi;
    r.lattice = p.size;
    r.grown = true;
  }

  // 4. The grid's cells and those the filled surface crosses, and a value at every corner.
  std::vector<VoxelKey> added;
  std::vector<std::pair<VoxelKey, float>> values, fallback;
  for (TileResult& t : results) {
    added.insert(added.end(), t.cells.begin(), t.cells.end());
    values.insert(values.end(), t.values.begin(), t.values.end());
    fallback.insert(fallback.end(), t.fallback.begin(), t.fallback.end());
    r.observed += t.counts.observed;
    r.seen_empty += t.counts.seen_empty;
    r.through += t.counts.through;
    r.filled += t.counts.filled;
    r.levels = std::max(r.levels, t.counts.levels);
    r.indicator = r.indicator || t.counts.indicator;
    if (results.size() == 1) r.fill = t.counts.fill;
    r.held_out += t.counts.held_out;
    r.held_out_error_gradient += t.counts.held_out_error_gradient;
    r.held_out_error_diffusion += t.counts.held_out_error_diffusion;
    r.held_out_error_indicator += t.counts.held_out_error_indicator;
    t = TileResult{};
  }
  if (choice.held_out > 0) {  // the automatic choice made on the first lattice
    r.held_out = choice.held_out;
    r.held_out_error_gradient = choice.held_out_error_gradient;
    r.held_out_error_diffusion = choice.held_out_error_diffusion;
    r.held_out_error_indicator = choice.held_out_error_indicator;
  }
  tbb::parallel_sort(added.begin(), added.end());
  // Tiles sharing a face hold its nodes at the same values (data, or the coarse solution, which
  // a skipped tile's corners take too): any one of them does, a solved tile's first.
  const auto by_key = [](const auto& x, const auto& y) { return x.first < y.first; };
  const auto same_key = [](const auto& x, const auto& y) { return x.first == y.first; };
  for (auto* v : {&values, &fallback}) {
    tbb::parallel_sort(v->begin(), v->end(), by_key);
    v->erase(std::unique(v->begin(), v->end(), same_key), v->end());
  }
  r.cells_added = added.size();
  out.grid = close_grid_with_cells(grid, added);
  out.distance.values.resize(out.grid.corners.size());
  out.distance.valid.assign(out.grid.corners.size(), 1);
  tbb::parallel_for(std::size_t{0}, out.grid.corners.size(), [&](std::size_t c) {
    const VoxelKey key = out.grid.corners[c];
    const auto find = [key](const std::vector<std::pair<VoxelKey, float>>& v, float& value) {
      const auto at = std::lower_bound(v.begin(), v.end(), key,
                                       [](const auto& x, VoxelKey k) { return x.first < k; });
      if (at == v.end() || at->first != key) return false;
      value = at->second;
      return true;
    };
    // Every corner is one of the grid's or of a crossed cell's: one of the two has it.
    float value = p.outside;
    if (!find(values, value)) find(fallback, value);
    out.distance.values[c] = value;
  });
  out.distance.disagreeing = field.disagreeing;
  out.distance.extrapolated = field.extrapolated;
  r.ran = true;
  if (report != nullptr) *report = r;
  return out;
}

}  // namespace meshflow
