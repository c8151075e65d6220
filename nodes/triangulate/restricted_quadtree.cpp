#include "nodes/triangulate/restricted_quadtree.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "nodes/triangulate/depth_noise.h"
#include "nodes/triangulate/quad_triangles.h"

namespace meshflow {
namespace {

// kBad: the block holds an invalid pixel or reaches past the image border; kEmpty: it holds
// no valid pixel. Blocks outside the image are both.
enum BlockState : std::uint8_t { kCenter = 1, kSplit = 2, kEmpty = 4, kBad = 8 };

class Quadtree {
 public:
  Quadtree(const PointGrid& g, const OcclusionTriangleTest& keep, float threshold_per_depth2)
      : g_(g), keep_(keep), threshold_per_depth2_(threshold_per_depth2), mid_(g.points.size(), 0) {
    root_ = 2;
    while (root_ < g.width - 1 || root_ < g.height - 1) root_ *= 2;
  }

  std::vector<Triangle> run() {
    for (int s = 2; s <= root_; s *= 2) select_level(s);
    std::vector<Triangle> out;
    for (int s = root_; s >= 2; s /= 2) emit_level(s, out);
    return out;
  }

 private:
  int blocks(int s) const { return root_ / s; }
  // Blocks of size s that reach into the image along x / y (the others are empty).
  int blocks_x(int s) const { return (g_.width - 1 + s - 1) / s; }
  int blocks_y(int s) const { return (g_.height - 1 + s - 1) / s; }
  std::uint8_t& state(int s, int bx, int by) {
    return states_[level(s)][static_cast<std::size_t>(by) * static_cast<std::size_t>(blocks(s)) +
                             static_cast<std::size_t>(bx)];
  }
  const std::uint8_t* state_row(int s, int by) const {
    return states_[level(s)].data() +
           static_cast<std::size_t>(by) * static_cast<std::size_t>(blocks(s));
  }
  static std::size_t level(int s) {
    std::size_t l = 0;
    while ((2 << l) < s) ++l;
    return l;
  }
  const Eigen::Vector3f& p(int u, int v) const { return g_.points[g_.index(u, v)]; }
  // Needed: farther from `approx` than the threshold x depth^2 (compared squared). A value
  // copied into each pass, so the passes' byte stores cannot make the compiler reload it.
  struct NeededTest {
    Eigen::Vector3f eye;
    float threshold_per_depth2;
    bool operator()(const Eigen::Vector3f& x, const Eigen::Vector3f& approx) const {
      const float threshold = threshold_per_depth2 * (x - eye).squaredNorm();
      return (x - approx).squaredNorm() > threshold * threshold;
    }
  };
  // True when the (u0, v0)-(u1, v1) diagonal is the shorter one of block (x0, y0, s).
  bool main_diagonal_shorter(int x0, int y0, int s) const {
    return (p(x0, y0) - p(x0 + s, y0 + s)).squaredNorm() <=
           (p(x0 + s, y0) - p(x0, y0 + s)).squaredNorm();
  }
  // The size-2 blocks of row `by` (3 x 3 pixels each): invalid pixels per column of the row's
  // three pixel rows (rows past the border count as invalid), summed over each block's three
  // columns. A bad block that is not empty is split (triangulated per pixel quad).
  void pixel_block_states(int by, std::uint8_t* states) const {
    thread_local std::vector<std::uint8_t> column_storage;
    const int width = g_.width, y0 = 2 * by;
    column_storage.assign(static_cast<std::size_t>(width) + 2, 3);  // 2 columns past the border
    std::uint8_t* column = column_storage.data();
    for (int y = y0; y < y0 + 3; ++y) {
      if (y >= g_.height) continue;  // stays 3 per column
      const Eigen::Vector3f* row = &g_.points[g_.index(0, y)];
      for (int x = 0; x < width; ++x)
        column[x] = static_cast<std::uint8_t>(column[x] - (std::isnan(row[x].x()) ? 0 : 1));
    }
    for (int bx = 0, nx = blocks_x(2); bx < nx; ++bx) {
      const int x0 = 2 * bx;
      const int invalid = column[x0] + column[x0 + 1] + column[x0 + 2];
      states[bx] = invalid == 9  ? static_cast<std::uint8_t>(kEmpty | kBad)
                   : invalid > 0 ? static_cast<std::uint8_t>(kBad | kCenter | kSplit)
                                 : std::uint8_t{0};
    }
  }

  // Level s in three passes, each parallel over rows with one writer per value: block states
  // (empty / split), then every edge midpoint once, then block centres.
  void select_level(int s) {
    const int n = blocks(s);
    states_.emplace_back(static_cast<std::size_t>(n) * static_cast<std::size_t>(n), kEmpty | kBad);
    block_states(s);
    edge_midpoints(s);
    block_centres(s);
  }

  // States of level s: bad / empty from the pixels at size 2, from the four children above
  // (their closed squares cover the block's); split when bad or a child has a centre.
  void block_states(int s) {
    const int h = s / 2, nx = blocks_x(s), ny = blocks_y(s);
    tbb::parallel_for(0, ny, [&](int by) {
      std::uint8_t* states = &state(s, 0, by);
      if (s == 2) {
        pixel_block_states(by, states);
      } else {
        const std::uint8_t* upper = &state(h, 0, 2 * by);
        const std::uint8_t* lower = &state(h, 0, 2 * by + 1);
        for (int bx = 0; bx < nx; ++bx) {
          const std::uint8_t c[4] = {upper[2 * bx], upper[2 * bx + 1], lower[2 * bx],
                                     lower[2 * bx + 1]};
          const std::uint8_t any = c[0] | c[1] | c[2] | c[3];
          const std::uint8_t all = c[0] & c[1] & c[2] & c[3];
          std::uint8_t st = static_cast<std::uint8_t>((any & kBad) | (all & kEmpty));
          if (!(st & kEmpty) && (any & (kBad | kCenter))) st |= kCenter | kSplit;
          states[bx] = st;
        }
      }
    });
  }

  // Midpoints of level s: of the edge between a block and its neighbour (outside blocks are
  // empty). A refined neighbour uses the midpoint as a corner; otherwise, with a clean block on
  // either side (all its pixels valid, so the edge's are), the midpoint is needed when it lies
  // too far from the edge's chord. Rows of blocks in parallel; every midpoint has one writer.
  void edge_midpoints(int s) {
    const int h = s / 2, nx = blocks_x(s), ny = blocks_y(s);
    const NeededTest needed{g_.eye, threshold_per_depth2_};
    auto decide = [needed](std::uint8_t one, std::uint8_t other, const Eigen::Vector3f& m,
                           const Eigen::Vector3f& a, const Eigen::Vector3f& b) -> std::uint8_t {
      if ((one | other) & kSplit) return 1;
      const bool clean = !(one & kEmpty) || !(other & kEmpty);
      return clean && needed(m, (a + b) / 2) ? 1 : 0;
    };
    const std::uint8_t outside = kEmpty | kBad;
    // Sizes captured by value: the passes' byte stores could alias members and captured
    // references, which the compiler would otherwise reload after every store.
    const int width = g_.width, height = g_.height;
    tbb::parallel_for(0, ny + 1, [&, s, h, nx, ny, width, height](int by) {
      const int y0 = by * s;
      const std::uint8_t* upper = by > 0 ? &state(s, 0, by - 1) : nullptr;
      const std::uint8_t* lower = by < ny ? &state(s, 0, by) : nullptr;
      if (y0 < height) {  // horizontal edges on top of the blocks of row by
        const Eigen::Vector3f* row = &g_.points[g_.index(0, y0)];
        std::uint8_t* mids = &mid_[g_.index(0, y0)];
        for (int bx = 0, x0 = 0; bx < nx && x0 + h < width; ++bx, x0 += s)
          mids[x0 + h] =
              decide(upper != nullptr ? upper[bx] : outside, lower != nullptr ? lower[bx] : outside,
                     row[x0 + h], row[x0], row[std::min(x0 + s, width - 1)]);
      }
      if (lower != nullptr && y0 + h < height) {  // vertical edges left of the blocks
        const Eigen::Vector3f* top = &g_.points[g_.index(0, y0)];
        const Eigen::Vector3f* middle = &g_.points[g_.index(0, y0 + h)];
        const Eigen::Vector3f* bottom = &g_.points[g_.index(0, std::min(y0 + s, height - 1))];
        std::uint8_t* mids = &mid_[g_.index(0, y0 + h)];
        for (int bx = 0, x0 = 0; bx <= nx && x0 < width; ++bx, x0 += s)
          mids[x0] = decide(bx > 0 ? lower[bx - 1] : outside, bx < nx ? lower[bx] : outside,
                            middle[x0], top[x0], bottom[x0]);
      }
    });
  }

  // Centres of level s: needed themselves, or by a needed midpoint of the block's edges. Only
  // blocks that are neither empty nor split get one, and those lie inside the image with every
  // pixel valid, so their rows are read directly.
  void block_centres(int s) {
    const int h = s / 2, nx = blocks_x(s), ny = blocks_y(s);
    const NeededTest needed{g_.eye, threshold_per_depth2_};
    const int height = g_.height;
    tbb::parallel_for(0, ny, [&, needed, s, h, nx, height](int by) {
      const int y0 = by * s, y1 = std::min(y0 + s, height - 1), ym = std::min(y0 + h, y1);
      const std::uint8_t* mid_top = &mid_[g_.index(0, y0)];
      const std::uint8_t* mid_middle = &mid_[g_.index(0, ym)];
      const std::uint8_t* mid_bottom = &mid_[g_.index(0, y1)];
      const Eigen::Vector3f* top = &g_.points[g_.index(0, y0)];
      const Eigen::Vector3f* middle = &g_.points[g_.index(0, ym)];
      const Eigen::Vector3f* bottom = &g_.points[g_.index(0, y1)];
      std::uint8_t* states = &state(s, 0, by);
      for (int bx = 0; bx < nx; ++bx) {
        if (states[bx] & (kEmpty | kSplit)) continue;
        const int x0 = bx * s, x1 = x0 + s, xm = x0 + h;
        // Branch-free: on noisy frames both the diagonal's choice and the test's outcome are
        // coin tosses, and branches on them mispredict half the time. The shorter diagonal's
        // ends are picked by index arithmetic (a select would be compiled to a branch).
        const int main = static_cast<int>((top[x0] - bottom[x1]).squaredNorm() <=
                                          (top[x1] - bottom[x0]).squaredNorm());
        const int top_end = x1 - main * s, bottom_end = x0 + main * s;
        const bool center = (mid_top[xm] | mid_bottom[xm] | mid_middle[x0] | mid_middle[x1]) |
                            needed(middle[xm], (top[top_end] + bottom[bottom_end]) / 2);
        states[bx] = static_cast<std::uint8_t>(states[bx] | (center ? kCenter : 0));
      }
    });
  }

  // Appends triangle (u0, v0), (u1, v1), (u2, v2) of an image `width` pixels wide (a copy: the
  // stores into `out` could alias the grid's); its pixels must be inside the image and valid
  // (corners of a block that is not split). The occlusion test runs per row, later.
  static void add_valid(std::vector<Triangle>& out, int width, int u0, int v0, int u1, int v1,
                        int u2, int v2) {
    out.push_back(Triangle{static_cast<std::uint32_t>(v0 * width + u0),
                           static_cast<std::uint32_t>(v1 * width + u1),
                           static_cast<std::uint32_t>(v2 * width + u2)});
  }

  // The leaves of level s that pass the occlusion test, rows in parallel, appended to `out` in
  // row order.
  void emit_level(int s, std::vector<Triangle>& all) {
    const auto ny = static_cast<std::size_t>(blocks_y(s));
    if (rows_.size() < ny) rows_.resize(ny);  // kept across levels: no reallocation
    tbb::parallel_for(std::size_t{0}, ny, [&](std::size_t by) {
      rows_[by].clear();
      emit_row(s, static_cast<int>(by), rows_[by]);
      keep_.filter(g_, rows_[by], 0);
    });
    std::size_t total = all.size();
    for (std::size_t by = 0; by < ny; ++by) total += rows_[by].size();
    all.reserve(total);
    for (std::size_t by = 0; by < ny; ++by)
      all.insert(all.end(), rows_[by].begin(), rows_[by].end());
  }

  void emit_row(int s, int by, std::vector<Triangle>& out) const {
    const int nx = blocks_x(s), width = g_.width;
    const std::uint8_t* states = state_row(s, by);
    const std::uint8_t* parents = s == root_ ? nullptr : state_row(2 * s, by / 2);
    for (int bx = 0; bx < nx; ++bx) {
      const std::uint8_t st = states[bx];
      if (st & kEmpty) continue;
      if (parents != nullptr && !(parents[bx / 2] & kSplit)) continue;  // a leaf above
      const int x0 = bx * s, y0 = by * s, h = s / 2;
      if (st & kSplit) {
        if (s == 2)  // holds an invalid pixel: per pixel quad inside the image, as naive
          for (int v = y0; v < std::min(y0 + 2, g_.height - 1); ++v)
            for (int u = x0; u < std::min(x0 + 2, width - 1); ++u)
              append_quad_triangles(g_, u, v, out);
        continue;  // otherwise the children are emitted at the next level
      }
      // From here the block is neither empty nor split: inside the image, every pixel valid.
      if (st & kCenter) {  // fan around the centre through the needed midpoints
        const int cu = x0 + h, cv = y0 + h;
        const std::array<std::array<int, 2>, 8> ring = {{{x0, y0},
                                                         {x0, y0 + h},
                                                         {x0, y0 + s},
                                                         {x0 + h, y0 + s},
                                                         {x0 + s, y0 + s},
                                                         {x0 + s, y0 + h},
                                                         {x0 + s, y0},
                                                         {x0 + h, y0}}};
        std::array<std::array<int, 2>, 8> used{};
        int k = 0;
        for (int i = 0; i < 8; ++i) {
          const auto& corner = ring[static_cast<std::size_t>(i)];
          if (i % 2 == 0 || mid_[static_cast<std::size_t>(corner[1] * width + corner[0])] != 0)
            used[static_cast<std::size_t>(k++)] = corner;
        }
        for (int i = 0; i < k; ++i) {
          const auto& a = used[static_cast<std::size_t>(i)];
          const auto& b = used[static_cast<std::size_t>(i + 1 < k ? i + 1 : 0)];
          add_valid(out, width, cu, cv, a[0], a[1], b[0], b[1]);
        }
        continue;
      }
      if (main_diagonal_shorter(x0, y0, s)) {
        add_valid(out, width, x0, y0, x0, y0 + s, x0 + s, y0 + s);
        add_valid(out, width, x0, y0, x0 + s, y0 + s, x0 + s, y0);
      } else {
        add_valid(out, width, x0, y0, x0, y0 + s, x0 + s, y0);
        add_valid(out, width, x0 + s, y0, x0, y0 + s, x0 + s, y0 + s);
      }
    }
  }

  const PointGrid& g_;
  const OcclusionTriangleTest& keep_;
  float threshold_per_depth2_;
  std::vector<std::uint8_t> mid_;                  // per pixel: a needed midpoint
  std::vector<std::vector<std::uint8_t>> states_;  // per level (size 2, 4, ...), per block
  std::vector<std::vector<Triangle>> rows_;        // emit_level()'s triangles per block row
  int root_ = 2;
};

}  // namespace

float quadtree_threshold_per_depth2(const PointGrid& grid, const QuadtreeConfig& config) {
  if (!(config.noise_multiple > 0.0f)) return config.error_per_depth2;
  return std::max(config.error_per_depth2, config.noise_multiple * estimate_noise_per_depth2(grid));
}

std::vector<Triangle> restricted_quadtree_triangles(const PointGrid& grid,
                                                    const OcclusionTriangleTest& keep,
                                                    const QuadtreeConfig& config,
                                                    float* threshold_used) {
  if (grid.width < 2 || grid.height < 2) return {};
  const float threshold = quadtree_threshold_per_depth2(grid, config);
  if (threshold_used != nullptr) *threshold_used = threshold;
  return Quadtree(grid, keep, threshold).run();
}

}  // namespace meshflow
