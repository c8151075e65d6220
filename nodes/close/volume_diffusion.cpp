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
  for (int s = 0; s < sweeps; ++s) {
    for (int colour = 0; colour < 2; ++colour) {
      tbb::parallel_for(0, n.z(), [&](int z) {
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
            l.values[i] = sum / static_cast<float>(count);
          }
        }
      });
    }
  }
}

// Which axes the next coarser level halves: those of at least 3 nodes (a flat lattice keeps
// coarsening along its long axes; its short one stays as it is).
Eigen::Vector3i coarsening_steps(const Eigen::Vector3i& size) {
  return Eigen::Vector3i(size.x() >= 3 ? 2 : 1, size.y() >= 3 ? 2 : 1, size.z() >= 3 ? 2 : 1);
}

// The lattice of half the resolution along the axes `step` halves: node c stands for fine node
// step * c; it is held when a fine node within one step of it (along the halved axes) is, at the
// mean of those nodes' values.
DiffusionLattice restrict_fixed(const DiffusionLattice& fine, const Eigen::Vector3i& step) {
  DiffusionLattice coarse;
  coarse.size = (fine.size.array() + step.array() - 1) / step.array();
  coarse.values.assign(coarse.node_count(), 0.0f);
  coarse.fixed.assign(coarse.node_count(), 0);
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
  const Eigen::Vector3i m = coarse.size;
  tbb::parallel_for(0, fine.size.z(), [&](int z) {
    for (int y = 0; y < fine.size.y(); ++y) {
      for (int x = 0; x < fine.size.x(); ++x) {
        const std::size_t i = fine.index(x, y, z);
        if (fine.fixed[i]) continue;
        const int p[3] = {x, y, z};
        int lo[3], hi[3];
        float w[3];
        for (int a = 0; a < 3; ++a) {
          lo[a] = std::min(p[a] / step[a], m[a] - 1);
          hi[a] = std::min(lo[a] + 1, m[a] - 1);
          w[a] = step[a] == 2 && (p[a] & 1) && hi[a] != lo[a] ? 0.5f : 0.0f;
        }
        float v = 0.0f;
        for (int corner = 0; corner < 8; ++corner) {
          float weight = 1.0f;
          int q[3];
          for (int a = 0; a < 3; ++a) {
            const bool upper = (corner >> a) & 1;
            q[a] = upper ? hi[a] : lo[a];
            weight *= upper ? w[a] : 1.0f - w[a];
          }
          if (weight > 0.0f) v += weight * coarse.values[coarse.index(q[0], q[1], q[2])];
        }
        fine.values[i] = v;
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

int diffuse_free_nodes(DiffusionLattice& lattice, const DiffusionConfig& config) {
  if (lattice.node_count() == 0) return 0;
  if (std::none_of(lattice.fixed.begin(), lattice.fixed.end(), [](std::uint8_t f) { return f; })) {
    std::fill(lattice.values.begin(), lattice.values.end(), 0.0f);
    return 0;
  }
  return diffuse_levels(lattice, config);
}

}  // namespace meshflow
