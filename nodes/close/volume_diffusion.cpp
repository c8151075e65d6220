#include "nodes/close/volume_diffusion.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace meshflow {
namespace {

// Sweeps of red-black Gauss-Seidel over the free nodes: a node of one colour reads only nodes
// of the other, so the planes of one colour may run in any order.
void diffusion_sweeps(DiffusionLattice& l, int sweeps) {
  const Eigen::Vector3i n = l.size;
  const bool poisson = !l.source.empty();
  const auto plane = [&](int z, int colour) {
    for (int y = 0; y < n.y(); ++y) {
      for (int x = (y + z + colour) & 1; x < n.x(); x += 2) {
        const std::size_t i = l.index(x, y, z);
        if (l.fixed[i]) continue;
        float sum = 0.0f;
        int count = 0;
        if (x > 0) sum += l.values[i - 1], ++count;
        if (x + 1 < n.x()) sum += l.values[i + 1], ++count;
        if (y > 0) sum += l.values[l.index(x, y - 1, z)], ++count;
        if (y + 1 < n.y()) sum += l.values[l.index(x, y + 1, z)], ++count;
        if (z > 0) sum += l.values[l.index(x, y, z - 1)], ++count;
        if (z + 1 < n.z()) sum += l.values[l.index(x, y, z + 1)], ++count;
        if (poisson) sum += l.source[i];
        l.values[i] = sum / static_cast<float>(count);
      }
    }
  };
  // A small level's planes are too short to share out: the tasks would cost more than the
  // sweep (the coarsest level's hundreds of sweeps over a few hundred nodes).
  const bool parallel = l.node_count() >= (std::size_t{1} << 15);
  for (int s = 0; s < sweeps; ++s) {
    for (int colour = 0; colour < 2; ++colour) {
      if (parallel)
        tbb::parallel_for(0, n.z(), [&](int z) { plane(z, colour); });
      else
        for (int z = 0; z < n.z(); ++z) plane(z, colour);
    }
  }
}

// Which axes the next coarser level halves: those of at least 3 nodes (a flat lattice keeps
// coarsening along its long axes; its short one stays as it is).
Eigen::Vector3i coarsening_steps(const Eigen::Vector3i& size) {
  return Eigen::Vector3i(size.x() >= 3 ? 2 : 1, size.y() >= 3 ? 2 : 1, size.z() >= 3 ? 2 : 1);
}

// The coarse level's source (the Poisson equation's right-hand side): each fine node's source
// shared among the coarse nodes around it by the trilinear weights of prolong_free() (so the
// sum is kept), halved as the spacing doubles (the equation is scaled by the spacing squared,
// the source by its volume: 2^2 / 2^3).
std::vector<float> restrict_source(const DiffusionLattice& fine, const Eigen::Vector3i& step,
                                   const Eigen::Vector3i& coarse_size) {
  const auto index = [&](int x, int y, int z) {
    return (static_cast<std::size_t>(z) * static_cast<std::size_t>(coarse_size.y()) +
            static_cast<std::size_t>(y)) *
               static_cast<std::size_t>(coarse_size.x()) +
           static_cast<std::size_t>(x);
  };
  std::vector<float> coarse(static_cast<std::size_t>(coarse_size.prod()), 0.0f);
  // Coarse plane z gathers from fine planes within one step of step.z() * z: each coarse node
  // sums its own contributions, so the planes run in parallel and the sums in a fixed order.
  tbb::parallel_for(0, coarse_size.z(), [&](int cz) {
    for (int cy = 0; cy < coarse_size.y(); ++cy)
      for (int cx = 0; cx < coarse_size.x(); ++cx) {
        const int c[3] = {cx, cy, cz};
        int from[3], to[3];
        for (int a = 0; a < 3; ++a) {
          from[a] = std::max(0, step[a] * c[a] - (step[a] - 1));
          to[a] = std::min(fine.size[a] - 1, step[a] * c[a] + (step[a] - 1));
        }
        float sum = 0.0f;
        for (int fz = from[2]; fz <= to[2]; ++fz)
          for (int fy = from[1]; fy <= to[1]; ++fy)
            for (int fx = from[0]; fx <= to[0]; ++fx) {
              const float s = fine.source[fine.index(fx, fy, fz)];
              if (s == 0.0f) continue;
              // The weight prolong_free() gives coarse node c at fine node f.
              const int f[3] = {fx, fy, fz};
              float weight = 1.0f;
              for (int a = 0; a < 3; ++a) {
                if (f[a] == step[a] * c[a]) continue;
                const int lo = std::min(f[a] / step[a], coarse_size[a] - 1);
                const int hi = std::min(lo + 1, coarse_size[a] - 1);
                // Past the last coarse node the fine node takes the last one's value.
                weight *= hi == lo ? (c[a] == lo ? 1.0f : 0.0f) : 0.5f;
              }
              sum += weight * s;
            }
        coarse[index(cx, cy, cz)] = sum;
      }
  });
  const float scale = step.maxCoeff() > 1 ? 0.5f : 1.0f;
  for (float& v : coarse) v *= scale;
  return coarse;
}

// The lattice of half the resolution along the axes `step` halves: node c stands for fine node
// step * c; it is held when a fine node within one step of it (along the halved axes) is, at the
// mean of those nodes' values.
DiffusionLattice restrict_fixed(const DiffusionLattice& fine, const Eigen::Vector3i& step) {
  DiffusionLattice coarse;
  coarse.size = (fine.size.array() + step.array() - 1) / step.array();
  coarse.values.assign(coarse.node_count(), 0.0f);
  coarse.fixed.assign(coarse.node_count(), 0);
  if (!fine.source.empty()) coarse.source = restrict_source(fine, step, coarse.size);
  const Eigen::Vector3i n = fine.size;
  const auto range = [&](int c, int a, int& from, int& to) {
    const int reach = step[a] - 1;  // 1 on a halved axis, 0 on a kept one
    from = std::max(0, step[a] * c - reach);
    to = std::min(n[a] - 1, step[a] * c + reach);
  };
  tbb::parallel_for(0, coarse.size.z(), [&](int z) {
    int z0, z1;
    range(z, 2, z0, z1);
    for (int y = 0; y < coarse.size.y(); ++y) {
      int y0, y1;
      range(y, 1, y0, y1);
      for (int x = 0; x < coarse.size.x(); ++x) {
        int x0, x1;
        range(x, 0, x0, x1);
        float sum = 0.0f;
        int count = 0;
        for (int fz = z0; fz <= z1; ++fz)
          for (int fy = y0; fy <= y1; ++fy)
            for (int fx = x0; fx <= x1; ++fx) {
              const std::size_t i = fine.index(fx, fy, fz);
              if (!fine.fixed[i]) continue;
              sum += fine.values[i];
              ++count;
            }
        if (count == 0) continue;
        const std::size_t c = coarse.index(x, y, z);
        coarse.fixed[c] = 1;
        coarse.values[c] = sum / static_cast<float>(count);
      }
    }
  });
  return coarse;
}

// Free nodes of `fine` take the trilinear interpolation of `coarse` at their position divided
// by `step` (restrict_fixed()'s).
void prolong_free(const DiffusionLattice& coarse, DiffusionLattice& fine,
                  const Eigen::Vector3i& step) {
  tbb::parallel_for(0, fine.size.z(), [&](int z) {
    for (int y = 0; y < fine.size.y(); ++y) {
      const CoarseRowInterpolation row(coarse, step, y, z);
      for (int x = 0; x < fine.size.x(); ++x) {
        const std::size_t i = fine.index(x, y, z);
        if (!fine.fixed[i]) fine.values[i] = row.at(x);
      }
    }
  });
}

int diffuse_levels(DiffusionLattice& lattice, const DiffusionConfig& config) {
  // Short axes stop halving, long ones go on: a flat lattice still reaches a coarsest level
  // of few nodes along every long axis, where its sweeps span the whole gap.
  const Eigen::Vector3i step = coarsening_steps(lattice.size);
  if (lattice.size.maxCoeff() <= std::max(2, config.coarsest_size) || step.maxCoeff() == 1) {
    for (std::size_t i = 0; i < lattice.values.size(); ++i)
      if (!lattice.fixed[i]) lattice.values[i] = 0.0f;
    diffusion_sweeps(lattice, config.coarsest_sweeps);
    return 1;
  }
  DiffusionLattice coarse = restrict_fixed(lattice, step);
  const int levels = diffuse_levels(coarse, config) + 1;
  prolong_free(coarse, lattice, step);
  diffusion_sweeps(lattice, config.sweeps_per_level);
  return levels;
}

}  // namespace

namespace {

// The coarse nodes around fine coordinate `fine` along an axis of `size` coarse nodes, coarse
// node c standing for fine node step x c, and the upper one's weight (0 past the last node).
void coarse_bracket(int fine, int step, int size, int& lo, int& hi, float& w) {
  lo = std::min(fine / step, size - 1);
  hi = std::min(lo + 1, size - 1);
  w = hi == lo ? 0.0f : static_cast<float>(fine - lo * step) / static_cast<float>(step);
}

}  // namespace

CoarseRowInterpolation::CoarseRowInterpolation(const DiffusionLattice& coarse,
                                               const Eigen::Vector3i& step, int y, int z)
    : coarse_(coarse), step_x_(step.x()) {
  int y0, y1, z0, z1;
  coarse_bracket(y, step.y(), coarse.size.y(), y0, y1, wy_);
  coarse_bracket(z, step.z(), coarse.size.z(), z0, z1, wz_);
  rows_[0] = coarse.index(0, y0, z0);
  rows_[1] = coarse.index(0, y1, z0);
  rows_[2] = coarse.index(0, y0, z1);
  rows_[3] = coarse.index(0, y1, z1);
}

float CoarseRowInterpolation::at(int x) const {
  int x0, x1;
  float wx;
  coarse_bracket(x, step_x_, coarse_.size.x(), x0, x1, wx);
  // The 8 corners in interpolate_coarse()'s order (x fastest), each weight the product of the
  // x, y and z factors in that order; corners of weight 0 are skipped.
  const float fx[2] = {1.0f - wx, wx}, fy[2] = {1.0f - wy_, wy_}, fz[2] = {1.0f - wz_, wz_};
  const int xs[2] = {x0, x1};
  float v = 0.0f;
  for (int corner = 0; corner < 8; ++corner) {
    const int a = corner & 1, b = (corner >> 1) & 1, c = (corner >> 2) & 1;
    const float weight = fx[a] * fy[b] * fz[c];
    if (weight > 0.0f)
      v += weight * coarse_.values[rows_[static_cast<std::size_t>(b + 2 * c)] +
                                   static_cast<std::size_t>(xs[a])];
  }
  return v;
}

float interpolate_coarse(const DiffusionLattice& coarse, const Eigen::Vector3i& step,
                         const Eigen::Vector3i& fine_node) {
  return CoarseRowInterpolation(coarse, step, fine_node.y(), fine_node.z()).at(fine_node.x());
}

int diffuse_free_nodes(DiffusionLattice& lattice, const DiffusionConfig& config) {
  if (lattice.node_count() == 0) return 0;
  if (lattice.source.empty() &&
      std::none_of(lattice.fixed.begin(), lattice.fixed.end(), [](std::uint8_t f) { return f; })) {
    std::fill(lattice.values.begin(), lattice.values.end(), 0.0f);
    return 0;
  }
  return diffuse_levels(lattice, config);
}

}  // namespace meshflow
