#include "nodes/close/gradient_fill.h"

#include <gtest/gtest.h>

#include <cmath>
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
  // everywhere, its divergence zero, and the potential the linear function itself.
  const auto plane = [](const Eigen::Vector3f& q) {
    return 0.6f * q.x() - 0.48f * q.y() + 0.64f * q.z() - 12.0f;
  };
  Problem p = make_problem(
      {33, 29, 25}, 2.0f, plane, [](const Eigen::Vector3f&) { return true; }, -1.0f);
  EXPECT_GE(gradient_fill(p.lattice, p.observed, 1.0f), 2);
  EXPECT_TRUE(p.lattice.source.empty());
  double worst = 0.0;
  for (int z = 0; z < 25; ++z)
    for (int y = 0; y < 29; ++y)
      for (int x = 0; x < 33; ++x) {
        const float exact = plane(
            Eigen::Vector3f(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)));
        worst = std::max(worst, static_cast<double>(
                                    std::abs(p.lattice.values[p.lattice.index(x, y, z)] - exact)));
      }
  EXPECT_LT(worst, 0.05) << "voxels";
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
  // A sphere of radius 14 voxels seen in a band of 2 voxels down to 7 voxels above its lowest
  // point (a turntable scan's unseen underside), the lattice's faces held outside at 3 voxels
  // as the close stage holds them. The gradient fill closes the cap near the sphere; diffusion
  // of the distance itself stays near its held values and closes it far inside.
  const Eigen::Vector3f centre(24.0f, 24.0f, 24.0f);
  const float radius = 14.0f;
  const auto sphere = [&](const Eigen::Vector3f& q) { return (q - centre).norm() - radius; };
  const auto seen = [&](const Eigen::Vector3f& q) { return q.z() >= centre.z() - 0.5f * radius; };
  Problem gradient = make_problem({49, 49, 49}, 2.0f, sphere, seen, 3.0f);
  Problem diffusion = gradient;
  gradient_fill(gradient.lattice, gradient.observed, 1.0f);
  diffuse_free_nodes(diffusion.lattice);
  const float exact = centre.z() - radius;
  const float by_gradient = crossing_below(gradient.lattice, 24, 24, 24);
  const float by_diffusion = crossing_below(diffusion.lattice, 24, 24, 24);
  EXPECT_NEAR(by_gradient, exact, 1.5f);
  EXPECT_GT(std::abs(by_diffusion - exact), 2.0f * std::abs(by_gradient - exact));
  // Inside, the fill goes down as a distance does (the diffused field of a sphere is about
  // (q - centre) / radius, its potential at the centre about -radius / 2; diffusion: a shallow
  // well near the band's values).
  EXPECT_LT(gradient.lattice.values[gradient.lattice.index(24, 24, 24)], -0.35f * radius);
}

}  // namespace
}  // namespace meshflow
