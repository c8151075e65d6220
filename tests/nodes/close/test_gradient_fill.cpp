#include "nodes/close/gradient_fill.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <functional>

namespace meshflow {
namespace {

// A lattice holding `f` at its faces (held, not observed) and at the nodes within `band` of
// f's zero set where `seen` says so (held and observed); the rest free at zero.
struct Problem {
  DiffusionLattice lattice;
  std::vector<std::uint8_t> observed;
};

Problem make_problem(const Eigen::Vector3i& size, float band,
                     const std::function<float(const Eigen::Vector3f&)>& f,
                     const std::function<bool(const Eigen::Vector3f&)>& seen, float face_value) {
  Problem p;
  DiffusionLattice& l = p.lattice;
  l.size = size;
  l.values.assign(l.node_count(), 0.0f);
  l.fixed.assign(l.node_count(), 0);
  p.observed.assign(l.node_count(), 0);
  for (int z = 0; z < size.z(); ++z)
    for (int y = 0; y < size.y(); ++y)
      for (int x = 0; x < size.x(); ++x) {
        const Eigen::Vector3f q(static_cast<float>(x), static_cast<float>(y),
                                static_cast<float>(z));
        const std::size_t i = l.index(x, y, z);
        const bool face = x == 0 || y == 0 || z == 0 || x + 1 == size.x() || y + 1 == size.y() ||
                          z + 1 == size.z();
        if (face) {
          l.fixed[i] = 1;
          l.values[i] = face_value < 0.0f ? f(q) : face_value;
        } else if (std::abs(f(q)) <= band && seen(q)) {
          l.fixed[i] = 1;
          p.observed[i] = 1;
          l.values[i] = f(q);
        }
      }
  return p;
}

TEST(GradientFill, ReproducesALinearDistance) {
  // A plane's distance (unit gradient) held on a band and on the faces: its gradient is the same
  // everywhere, its divergence zero, and the potential the linear function itself (up to the
  // solver's convergence: the default's quarter of 40 sweeps per level leaves more).
  const auto plane = [](const Eigen::Vector3f& q) {
    return 0.6f * q.x() - 0.48f * q.y() + 0.64f * q.z() - 12.0f;
  };
  for (const int sweeps : {40, 160}) {
    Problem p = make_problem(
        {33, 29, 25}, 2.0f, plane, [](const Eigen::Vector3f&) { return true; }, -1.0f);
    DiffusionConfig config;
    config.sweeps_per_level = sweeps;
    EXPECT_GE(gradient_fill(p.lattice, p.observed, 1.0f, config), 2);
    EXPECT_TRUE(p.lattice.source.empty());
    double worst = 0.0;
    for (int z = 0; z < 25; ++z)
      for (int y = 0; y < 29; ++y)
        for (int x = 0; x < 33; ++x) {
          const float exact = plane(
              Eigen::Vector3f(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)));
          worst = std::max(
              worst,
              static_cast<double>(std::abs(p.lattice.values[p.lattice.index(x, y, z)] - exact)));
        }
    std::printf("[ linear ] %d sweeps a level: largest error %.3f voxels\n", sweeps, worst);
    // The values span 0.6 x 32 + 0.48 x 28 + 0.64 x 24 = 47.9 voxels.
    EXPECT_LT(worst, sweeps == 40 ? 0.05 * 47.9 : 0.01 * 47.9) << "voxels";
  }
}

// The zero crossing of `l` going down the vertical line through (x, y) from z = top: the z where
// the values turn positive, linearly interpolated.
float crossing_below(const DiffusionLattice& l, int x, int y, int top) {
  for (int z = top; z > 0; --z) {
    const float a = l.values[l.index(x, y, z)], b = l.values[l.index(x, y, z - 1)];
    if (a < 0.0f && b >= 0.0f) return static_cast<float>(z) - a / (a - b);
  }
  return -1.0f;
}

TEST(GradientFill, CarriesASphereOnAcrossItsUnseenCap) {
  // A sphere of radius 14 voxels seen in a band of 2 voxels down to 3.5 voxels above its lowest
  // point (a turntable scan's unseen underside), on the lattice the close stage builds: the
  // data's box and 3 more nodes, its faces held outside at 3 voxels. The gradient fill closes
  // the cap near the sphere; diffusion of the distance itself domes it into the sphere.
  const float radius = 14.0f;
  const Eigen::Vector3f centre(radius + 5.0f, radius + 5.0f, 14.0f);
  const auto sphere = [&](const Eigen::Vector3f& q) { return (q - centre).norm() - radius; };
  const auto seen = [&](const Eigen::Vector3f& q) { return q.z() >= centre.z() - 0.75f * radius; };
  Problem gradient = make_problem({39, 39, 34}, 2.0f, sphere, seen, 3.0f);
  Problem diffusion = gradient;
  gradient_fill(gradient.lattice, gradient.observed, 1.0f);
  diffuse_free_nodes(diffusion.lattice);
  const float exact = centre.z() - radius;
  const int c = static_cast<int>(centre.x());
  const float by_gradient = crossing_below(gradient.lattice, c, c, 14);
  const float by_diffusion = crossing_below(diffusion.lattice, c, c, 14);
  std::printf(
      "[ sphere ] lowest point %.2f: gradient fill %.2f, diffusion %.2f; centre %.2f / %.2f\n",
      exact, by_gradient, by_diffusion, gradient.lattice.values[gradient.lattice.index(c, c, 14)],
      diffusion.lattice.values[diffusion.lattice.index(c, c, 14)]);
  // Measured: 2.3 voxels above the lowest point (which is on the lattice's face, held outside),
  // diffusion 4.8; at the centre -6.0 and -1.6 (the distance is -14).
  EXPECT_NEAR(by_gradient, exact, 2.5f);
  EXPECT_LT(std::abs(by_gradient - exact), std::abs(by_diffusion - exact));
  // Inside, the fill goes down as a distance does (the diffused field of a sphere is about
  // (q - centre) / radius, its potential at the centre about -radius / 2; diffusion: a shallow
  // well near the band's values).
  EXPECT_LT(gradient.lattice.values[gradient.lattice.index(c, c, 14)], -0.35f * radius);
}

// gradient_fill_reach() against analytic depths: a sphere of radius 12 nodes seen down to 4
// nodes above its bottom (the data's box 4 nodes above it) turns to close exactly 4 nodes below
// the box (the fitted turn of its normal is a circle of its radius); the sides it faces fully
// reach the sphere's extreme past their plane; a box's vertical walls seen down to the same plane
// never turn (infinite reach, or deeper than the lattice where rounding tilts them).
TEST(GradientFill, ReachIsTheDepthWhereTheObservedSurfaceTurnsToClose) {
  const Eigen::Vector3i size = Eigen::Vector3i::Constant(40);
  const Eigen::Vector3f c(20.0f, 20.0f, 20.0f);
  const float r = 12.0f;
  const float cut = 12.0f;  // seen where z >= 12; the sphere's bottom is at z = 8
  const auto seen = [&](const Eigen::Vector3f& q) { return q.z() >= cut; };
  const int margin = 8;  // faces at 0 and 39: the data's box from 8 (the sphere's extent)
  const Problem sphere = make_problem(
      size, 1.5f, [&](const Eigen::Vector3f& q) { return (q - c).norm() - r; }, seen, 5.0f);
  // The -z side's plane: the data's lowest observed node, z = 12 (margin 12 on that axis).
  const std::array<float, 6> reach =
      gradient_fill_reach(sphere.lattice, sphere.observed, 1.0f, margin, 8);
  // The planes at 8 and 31 (39 - 8): the sphere reaches 0 past the low ones, 1 past the high.
  for (const std::size_t side : {0, 1, 2, 3, 5})
    EXPECT_NEAR(reach[side], side % 2 == 0 ? 0.0f : 1.0f, 0.6f) << side;
  const std::array<float, 6> below =
      gradient_fill_reach(sphere.lattice, sphere.observed, 1.0f, 12, 8);
  std::printf("[ reach ] sphere cap below the data: %.2f nodes (exact 4)\n", below[4]);
  EXPECT_NEAR(below[4], 4.0f, 0.6f);

  const Problem box = make_problem(
      size, 1.5f,
      [&](const Eigen::Vector3f& q) { return ((q - c).cwiseAbs().array() - r).maxCoeff(); }, seen,
      5.0f);
  const std::array<float, 6> walls = gradient_fill_reach(box.lattice, box.observed, 1.0f, 12, 8);
  EXPECT_GT(walls[4], 40.0f);  // deeper than the lattice: no turn
}

}  // namespace
}  // namespace meshflow
