#include "nodes/close/volume_diffusion.h"

#include <gtest/gtest.h>

#include <cmath>

#include "test_support.h"

namespace meshflow {
namespace {

// A lattice whose faces and a few interior nodes hold a linear function (harmonic, so also
// the discrete Laplace equation's solution everywhere).
DiffusionLattice linear_lattice(const Eigen::Vector3i& size) {
  DiffusionLattice l;
  l.size = size;
  l.values.assign(l.node_count(), 0.0f);
  l.fixed.assign(l.node_count(), 0);
  for (int z = 0; z < size.z(); ++z)
    for (int y = 0; y < size.y(); ++y)
      for (int x = 0; x < size.x(); ++x) {
        const bool face = x == 0 || y == 0 || z == 0 || x + 1 == size.x() || y + 1 == size.y() ||
                          z + 1 == size.z();
        const bool inner = x == size.x() / 3 && y == size.y() / 2 && z == size.z() / 2;
        if (!face && !inner) continue;
        const std::size_t i = l.index(x, y, z);
        l.fixed[i] = 1;
        l.values[i] = 0.5f * static_cast<float>(x) - 0.25f * static_cast<float>(y) +
                      0.125f * static_cast<float>(z) - 3.0f;
      }
  return l;
}

TEST(VolumeDiffusion, FillsFreeNodesWithTheHarmonicSolution) {
  DiffusionLattice l = linear_lattice({65, 41, 23});
  const int levels = diffuse_free_nodes(l);
  EXPECT_GE(levels, 3);
  double worst = 0.0;
  for (int z = 0; z < l.size.z(); ++z)
    for (int y = 0; y < l.size.y(); ++y)
      for (int x = 0; x < l.size.x(); ++x) {
        const double exact = 0.5 * x - 0.25 * y + 0.125 * z - 3.0;
        worst = std::max(worst, std::abs(l.values[l.index(x, y, z)] - exact));
      }
  // The values span 0.5 * 64 + 0.25 * 40 + 0.125 * 22 = 44.75.
  EXPECT_LT(worst, 0.01 * 44.75) << "largest deviation from the harmonic solution";
}

// A flat lattice (two nodes thick, only its rim held): the levels go on halving the long axes
// (they once stopped at the first level because one axis was short, leaving 500 sweeps on
// 257 x 257 nodes, far from converged in the middle).
TEST(VolumeDiffusion, FlatLatticesCoarsenAlongTheirLongAxes) {
  DiffusionLattice l;
  l.size = {257, 257, 2};
  l.values.assign(l.node_count(), 0.0f);
  l.fixed.assign(l.node_count(), 0);
  const auto exact = [](int x, int y) { return 0.5 * x - 0.25 * y - 3.0; };
  for (int z = 0; z < 2; ++z)
    for (int y = 0; y < 257; ++y)
      for (int x = 0; x < 257; ++x) {
        if (x > 0 && y > 0 && x < 256 && y < 256) continue;
        l.fixed[l.index(x, y, z)] = 1;
        l.values[l.index(x, y, z)] = static_cast<float>(exact(x, y));
      }
  EXPECT_GE(diffuse_free_nodes(l), 5);
  double worst = 0.0;
  for (int y = 0; y < 257; ++y)
    for (int x = 0; x < 257; ++x)
      worst = std::max(worst, std::abs(l.values[l.index(x, y, 1)] - exact(x, y)));
  // The values span 0.5 * 256 + 0.25 * 256 = 192.
  EXPECT_LT(worst, 0.01 * 192) << "largest deviation from the harmonic solution";
}

TEST(VolumeDiffusion, HeldNodesKeepTheirValuesAndTheSignSeparatesTwoSources) {
  // An inside node (-1) in a box held at +1: the free nodes near it are negative, those near the
  // faces positive, and no held value changes.
  DiffusionLattice l;
  l.size = {21, 21, 21};
  l.values.assign(l.node_count(), 0.0f);
  l.fixed.assign(l.node_count(), 0);
  for (int z = 0; z < 21; ++z)
    for (int y = 0; y < 21; ++y)
      for (int x = 0; x < 21; ++x)
        if (x == 0 || y == 0 || z == 0 || x == 20 || y == 20 || z == 20) {
          l.fixed[l.index(x, y, z)] = 1;
          l.values[l.index(x, y, z)] = 1.0f;
        }
  for (int dz = -2; dz <= 2; ++dz)
    for (int dy = -2; dy <= 2; ++dy)
      for (int dx = -2; dx <= 2; ++dx) {
        l.fixed[l.index(10 + dx, 10 + dy, 10 + dz)] = 1;
        l.values[l.index(10 + dx, 10 + dy, 10 + dz)] = -1.0f;
      }
  const DiffusionLattice before = l;
  diffuse_free_nodes(l);
  for (std::size_t i = 0; i < l.node_count(); ++i)
    if (before.fixed[i]) {
      ASSERT_EQ(l.values[i], before.values[i]);
    }
  EXPECT_LT(l.values[l.index(13, 10, 10)], 0.0f);
  EXPECT_GT(l.values[l.index(18, 10, 10)], 0.0f);
  // Symmetric in the six directions.
  EXPECT_NEAR(l.values[l.index(14, 10, 10)], l.values[l.index(10, 6, 10)], 1e-3f);
}

// The Poisson equation: faces held at x^2 + y^2 + z^2, whose discrete Laplacian is 6
// everywhere (sum over neighbours of (value_i - value_j) = -6): the free nodes take the
// quadratic (the coarser levels' sources must scale with their spacing for this).
TEST(VolumeDiffusion, SolvesThePoissonEquationWithASource) {
  DiffusionLattice l;
  l.size = {49, 41, 33};
  l.values.assign(l.node_count(), 0.0f);
  l.fixed.assign(l.node_count(), 0);
  l.source.assign(l.node_count(), -6.0f);
  const Eigen::Vector3d centre(24.0, 20.0, 16.0);
  const auto exact = [&](int x, int y, int z) {
    return (Eigen::Vector3d(x, y, z) - centre).squaredNorm();
  };
  for (int z = 0; z < l.size.z(); ++z)
    for (int y = 0; y < l.size.y(); ++y)
      for (int x = 0; x < l.size.x(); ++x)
        if (x == 0 || y == 0 || z == 0 || x + 1 == l.size.x() || y + 1 == l.size.y() ||
            z + 1 == l.size.z()) {
          l.fixed[l.index(x, y, z)] = 1;
          l.values[l.index(x, y, z)] = static_cast<float>(exact(x, y, z));
        }
  EXPECT_GE(diffuse_free_nodes(l), 3);
  double worst = 0.0;
  for (int z = 0; z < l.size.z(); ++z)
    for (int y = 0; y < l.size.y(); ++y)
      for (int x = 0; x < l.size.x(); ++x)
        worst = std::max(worst, std::abs(l.values[l.index(x, y, z)] - exact(x, y, z)));
  // The faces' values span 24^2 + 20^2 + 16^2 = 1232 down to 256 (a face's middle).
  EXPECT_LT(worst, 0.01 * 1232) << "largest deviation from the quadratic";
}

// The trilinear blend reproduces a linear function wherever it samples (steps 1 and 2 mixed),
// and clamps past the coarse lattice's last node.
TEST(VolumeDiffusion, InterpolateCoarseIsExactForLinearFunctions) {
  DiffusionLattice coarse;
  coarse.size = {5, 4, 3};
  coarse.values.resize(coarse.node_count());
  coarse.fixed.assign(coarse.node_count(), 1);
  const Eigen::Vector3i step(2, 1, 2);
  const auto f = [](const Eigen::Vector3f& p) { return 0.5f * p.x() - 2.0f * p.y() + p.z() + 1; };
  for (int z = 0; z < 3; ++z)
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 5; ++x)
        coarse.values[coarse.index(x, y, z)] = f(Eigen::Vector3f(
            2.0f * static_cast<float>(x), static_cast<float>(y), 2.0f * static_cast<float>(z)));
  for (int z = 0; z <= 4; ++z)
    for (int y = 0; y <= 3; ++y)
      for (int x = 0; x <= 8; ++x)
        ASSERT_NEAR(
            interpolate_coarse(coarse, step, {x, y, z}),
            f(Eigen::Vector3f(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z))),
            1e-5f)
            << x << " " << y << " " << z;
  // Past the last node (x = 9 > 8): the last node's value.
  EXPECT_NEAR(interpolate_coarse(coarse, step, {9, 0, 0}), f(Eigen::Vector3f(8, 0, 0)), 1e-5f);
}

TEST(VolumeDiffusion, SameValuesForOneAndTwoThreads) {
  const auto run = [] {
    DiffusionLattice l = linear_lattice({40, 33, 27});
    l.values[l.index(5, 5, 5)] = 7.0f;  // a second source makes the solution non-linear
    l.fixed[l.index(5, 5, 5)] = 1;
    diffuse_free_nodes(l);
    return l.values;
  };
  EXPECT_EQ(test::with_threads(1, run), test::with_threads(2, run));
}

}  // namespace
}  // namespace meshflow
