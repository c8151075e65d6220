#include "nodes/normals/smallest_eigen.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace meshflow {
namespace {

// The angle between the lines of unit vectors a and b (rad), accurate near zero.
double line_angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), std::abs(a.dot(b)));
}

// The scatter (sum of outer products about the mean) of `points`, as a plane fit builds it.
Eigen::Matrix3d scatter(const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d s = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& p : points) s += (p - mean) * (p - mean).transpose();
  return s;
}

// Ten points: `extent` scales the axes of a random frame (e.g. (1, 1, 1e-4) a noisy plane),
// centred at `offset`.
std::vector<Eigen::Vector3d> neighbourhood(std::mt19937& rng, const Eigen::Vector3d& extent,
                                           const Eigen::Vector3d& offset) {
  std::normal_distribution<double> g(0.0, 1.0);
  const Eigen::Matrix3d frame =
      Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
  std::vector<Eigen::Vector3d> points(10);
  for (Eigen::Vector3d& p : points)
    p = offset + frame * Eigen::Vector3d(g(rng), g(rng), g(rng)).cwiseProduct(extent);
  return points;
}

// Checks smallest_eigen(a) against Eigen's iterative solver (the oracle): the smallest
// eigenvalue within 1e-13 of the largest entry, the others within 1e-7 (where two nearly
// coincide the cubic keeps half the digits), a unit vector whose residual |a v - values[0] v|
// is within 1e-11 of the largest entry (where computeDirect answers, as the normals did before
// the closed form: both within 1e-7, its accuracy on near-double roots), and, when the two
// smallest eigenvalues are apart by gap > `min_gap` of the largest entry, the oracle's vector
// within 1e-13 / gap rad (both solvers' rounding is amplified by 1 / gap). Returns whether the
// closed form answered.
bool check(const Eigen::Matrix3d& a, double min_gap) {
  const SmallestEigen e = smallest_eigen(a);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> oracle(a);
  const double scale = std::max(a.cwiseAbs().maxCoeff(), 1e-300);
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(e.values[i], oracle.eigenvalues()[i],
                (i == 0 && e.closed_form ? 1e-13 : 1e-7) * scale)
        << "eigenvalue " << i;
  EXPECT_NEAR(e.vector.norm(), 1.0, 1e-12);
  EXPECT_LE((a * e.vector - e.values[0] * e.vector).norm(), (e.closed_form ? 1e-11 : 1e-7) * scale);
  const double gap = (oracle.eigenvalues()[1] - oracle.eigenvalues()[0]) / scale;
  if (gap > min_gap) {
    EXPECT_LE(line_angle(e.vector, oracle.eigenvectors().col(0)), 1e-13 / gap) << "gap " << gap;
  }
  return e.closed_form;
}

TEST(SmallestEigen, MatchesTheIterativeSolverOnRandomNeighbourhoods) {
  std::mt19937 rng(1);
  int closed = 0;
  for (int t = 0; t < 2000; ++t)
    closed += check(scatter(neighbourhood(rng, {1.0, 0.7, 0.4}, {3.0, -20.0, 1.5})), 1e-3);
  EXPECT_EQ(closed, 2000);
}

TEST(SmallestEigen, PlanarNeighbourhoodsGiveTheirPlaneNormalToTheLastBits) {
  std::mt19937 rng(2);
  int closed = 0;
  for (double thickness : {1e-2, 1e-4, 1e-6, 0.0})
    for (double aspect : {1.0, 0.3, 0.05})  // round, elongated patches
      for (int t = 0; t < 300; ++t) {
        const std::vector<Eigen::Vector3d> points =
            neighbourhood(rng, {0.05, 0.05 * aspect, thickness}, {12.0, 5.0, -0.7});
        closed += check(scatter(points), 1e-4);
      }
  EXPECT_EQ(closed, 4 * 3 * 300);
}

TEST(SmallestEigen, ExactPlaneAndIsotropicInPlaneSpread) {
  // A regular grid on the plane z = 0.3 x - 0.2 y: the two largest eigenvalues coincide (where
  // acos loses half its digits) and the smallest is zero.
  std::vector<Eigen::Vector3d> points;
  for (int i = -2; i <= 2; ++i)
    for (int j = -2; j <= 2; ++j)
      points.emplace_back(0.01 * i, 0.01 * j, 0.3 * 0.01 * i - 0.2 * 0.01 * j);
  const Eigen::Vector3d truth = Eigen::Vector3d(-0.3, 0.2, 1.0).normalized();
  const SmallestEigen e = smallest_eigen(scatter(points));
  EXPECT_TRUE(e.closed_form);
  EXPECT_LE(line_angle(e.vector, truth), 1e-13);
  EXPECT_NEAR(e.values[0], 0.0, 1e-18);
  check(scatter(points), 1e-4);
}

TEST(SmallestEigen, LinearNeighbourhoodsStillGiveUnitEigenvectors) {
  // Points along a line: the two smallest eigenvalues (nearly) coincide, any vector across the
  // line is an answer; tiny gaps go to computeDirect.
  std::mt19937 rng(3);
  int robust = 0;
  for (double width : {1e-2, 1e-4, 1e-7, 0.0})
    for (int t = 0; t < 300; ++t) {
      const double second = width * (t % 2 == 0 ? 1.0 : 1.0 + 1e-3);  // round or flat tubes
      robust += !check(scatter(neighbourhood(rng, {1.0, width, second}, {0.5, 0.5, 0.5})), 1e-3);
    }
  EXPECT_GT(robust, 0) << "exact lines take the robust path";
}

TEST(SmallestEigen, IsotropicAndDegenerateMatrices) {
  // Nearly multiples of I: perturbations of 1e-4 (closed form, gaps ~1e-4) down to 1e-10.
  std::mt19937 rng(4);
  std::normal_distribution<double> g(0.0, 1.0);
  for (double size : {1e-4, 1e-6, 1e-8, 1e-10})
    for (int t = 0; t < 300; ++t) {
      Eigen::Matrix3d r;
      for (int i = 0; i < 3; ++i)
        for (int j = i; j < 3; ++j) r(i, j) = r(j, i) = g(rng);
      check(2.5 * Eigen::Matrix3d::Identity() + size * r, 1e-5);
    }
  EXPECT_FALSE(smallest_eigen(Eigen::Matrix3d::Identity()).closed_form);
  const SmallestEigen zero = smallest_eigen(Eigen::Matrix3d::Zero());
  EXPECT_FALSE(zero.closed_form);
  EXPECT_NEAR(zero.vector.norm(), 1.0, 1e-12);
  EXPECT_EQ(zero.values, Eigen::Vector3d::Zero());
  // One point repeated (a zero scatter), two points (rank one), three (rank two).
  const Eigen::Vector3d p(1.0, 2.0, 3.0), q(1.5, 2.0, 2.0), s(0.0, 2.5, 3.0);
  check(scatter({p, p, p}), 1e-3);
  check(scatter({p, q, p, q}), 1e-3);
  EXPECT_TRUE(check(scatter({p, q, s}), 1e-3));
  // Axis-aligned and diagonal matrices (zero off-diagonal entries).
  EXPECT_TRUE(check(Eigen::Vector3d(3.0, 1.0, 2.0).asDiagonal().toDenseMatrix(), 1e-3));
  EXPECT_TRUE(check(Eigen::Vector3d(0.0, 1.0, 2.0).asDiagonal().toDenseMatrix(), 1e-3));
}

TEST(SmallestEigen, ScaleDoesNotMatter) {
  std::mt19937 rng(5);
  const Eigen::Matrix3d a = scatter(neighbourhood(rng, {1.0, 0.5, 0.01}, {0.0, 0.0, 0.0}));
  const SmallestEigen unit = smallest_eigen(a);
  for (double s : {1e-30, 1e-8, 1e12, 1e30}) {
    const SmallestEigen scaled = smallest_eigen(a * s);
    EXPECT_TRUE(scaled.closed_form);
    EXPECT_LE(line_angle(scaled.vector, unit.vector), 1e-13);
    EXPECT_NEAR(scaled.values[0] / s, unit.values[0], 1e-12 * unit.values[2]);
  }
}

}  // namespace
}  // namespace meshflow
