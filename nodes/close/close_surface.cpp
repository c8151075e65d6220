#include "nodes/close/close_surface.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <iterator>
#include <memory>
#include <utility>

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
  const DiffusionLattice* coarse = nullptr;
  int coarse_step = 1;
};

// Free nodes on one side of zero that no held node on that side reaches through free nodes
// of the same side (6-neighbours) flip to the other side: pockets of the fill, which would be
// extra components inside or beside the object (the double layer wobbles near the band's
// ends). Inside first (a pocket inside joins the outside next to it), then outside. Serial
// breadth-first fills; the set reached does not depend on the order. O(nodes).
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
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const std::size_t i = queue[head];
      const int x = static_cast<int>(i % static_cast<std::size_t>(n.x()));
      const int y =
          static_cast<int>(i / static_cast<std::size_t>(n.x()) % static_cast<std::size_t>(n.y()));
      const int z = static_cast<int>(i / (static_cast<std::size_t>(n.x()) * n.y()));
      const auto visit = [&](std::size_t j) {
        if (reached[j] || l.fixed[j] || !side(j)) return;
        reached[j] = 1;
        queue.push_back(j);
      };
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
  // A whole lattice of a cloud's distances: the indicator's fill; a tile: diffusion between
  // its faces, which hold the coarse solution (the double layer needs the whole surface). A
  // fused map (no points) is diffused too: its observed voxels fill the truncation band on
  // both sides, and the double layer of its ragged band's ends left small extra shells
  // (CliClose.FusedAndMergedDepthSequencesCloseWatertight).
  float grow_below = 0.0f;  // a free node on the data's box below this: the lattice is too small
  const bool indicator = p.config->indicator_fill && p.coarse == nullptr && !p.cloud->empty();
  if (indicator) {
    // Lines through observed tunnels are held outside like lines of sight: the double layer
    // of an open tunnel's upper part would cap it where its walls were unseen.
    const float stop = p.config->free_space_stop_voxels * p.grid->voxel_size;
    std::vector<std::uint8_t> side(l.node_count(), 0);
    tbb::parallel_for(std::size_t{0}, side.size(), [&](std::size_t i) {
      if (observed[i]) side[i] = l.values[i] > 0.0f ? 1 : 2;
    });
    const std::vector<std::uint8_t> through = through_line_nodes(n, side);
    out.counts.through = hold_outside(
        l, stop, [&](std::size_t i) { return through[i] != 0; }, owned);
  }
  if (indicator)
    out.counts.levels =
        close_fill_by_indicator(l, observed, p.grid->voxel_size, p.config->diffusion, grow_below);
  else
    out.counts.levels = diffuse_free_nodes(l, p.config->diffusion);
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
        if (!(l.values[i] < grow_below) || p.coarse != nullptr) continue;
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

// A grid of the given sorted cells: their corners (sorted, unique) and each cell's corner
// indices.
SparseGrid close_grid_of_cells(std::vector<VoxelKey> cells, float voxel) {
  SparseGrid grid;
  grid.voxel_size = voxel;
  grid.cells = std::move(cells);
  std::vector<VoxelKey> corners(grid.cells.size() * 8);
  tbb::parallel_for(std::size_t{0}, grid.cells.size(), [&](std::size_t i) {
    const Eigen::Vector3i c = unpack_key(grid.cells[i]);
    for (int k = 0; k < 8; ++k)
      corners[i * 8 + static_cast<std::size_t>(k)] =
          pack_key(c + Eigen::Vector3i(k & 1, (k >> 1) & 1, (k >> 2) & 1));
  });
  tbb::parallel_sort(corners.begin(), corners.end());
  corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
  grid.corners = std::move(corners);
  grid.cell_corners.resize(grid.cells.size());
  tbb::parallel_for(std::size_t{0}, grid.cells.size(), [&](std::size_t i) {
    const Eigen::Vector3i c = unpack_key(grid.cells[i]);
    for (int k = 0; k < 8; ++k)
      grid.cell_corners[i][static_cast<std::size_t>(k)] =
          grid.find_corner(c + Eigen::Vector3i(k & 1, (k >> 1) & 1, (k >> 2) & 1));
  });
  return grid;
}

// The tiles of side `cells` along one axis of `nodes` nodes: tile t spans nodes
// [t cells, min((t + 1) cells, nodes - 1)]; neighbours share a face.
int close_tile_count(int nodes, int cells) { return std::max(1, (nodes - 2) / cells + 1); }

}  // namespace

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
  // 1. The lattice: the grid's corners grown by the margin.
  Eigen::Vector3i lo = unpack_key(grid.corners.front()), hi = lo;
  for (VoxelKey k : grid.corners) {
    const Eigen::Vector3i c = unpack_key(k);
    lo = lo.cwiseMin(c);
    hi = hi.cwiseMax(c);
  }
  const int margin = std::max(1, static_cast<int>(std::ceil(config.margin_voxels)));
  lo.array() -= margin;
  hi.array() += margin;
  CloseProblem p;
  p.grid = &grid;
  p.field = &field;
  p.cloud = &cloud;
  p.config = &config;
  p.lo = lo;
  p.size = hi - lo + Eigen::Vector3i::Ones();
  p.outside = static_cast<float>(margin) * voxel;
  p.margin = margin;
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
    std::vector<std::vector<std::uint32_t>> tile_corners(tile_count);
    for (std::uint32_t c = 0; c < grid.corners.size(); ++c) {
      const Eigen::Vector3i q = unpack_key(grid.corners[c]) - lo;
      Eigen::Vector3i first, last;
      for (int a = 0; a < 3; ++a) {
        last[a] = std::min(q[a] / cells, tiles[a] - 1);
        first[a] = q[a] % cells == 0 && q[a] > 0 ? q[a] / cells - 1 : last[a];
      }
      for (int z = first.z(); z <= last.z(); ++z)
        for (int y = first.y(); y <= last.y(); ++y)
          for (int x = first.x(); x <= last.x(); ++x)
            tile_corners[tile_index({x, y, z})].push_back(c);
    }

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
    Eigen::Vector3i grow_lo = Eigen::Vector3i::Zero(), grow_hi = Eigen::Vector3i::Zero();
    for (int k = 0; k < 3; ++k) {
      const int g = std::max(margin, p.size[k] / 4);
      if (results.front().cut[static_cast<std::size_t>(2 * k)]) grow_lo[k] = g;
      if (results.front().cut[static_cast<std::size_t>(2 * k + 1)]) grow_hi[k] = g;
    }
    if ((grow_lo + grow_hi).maxCoeff() == 0 || nodes_of(p.size + grow_lo + grow_hi) > limit) break;
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
    t = TileResult{};
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
  std::vector<VoxelKey> all_cells;
  all_cells.reserve(grid.cells.size() + added.size());
  std::merge(grid.cells.begin(), grid.cells.end(), added.begin(), added.end(),
             std::back_inserter(all_cells));
  out.grid = close_grid_of_cells(std::move(all_cells), voxel);
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
