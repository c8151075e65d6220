#include "nodes/normals/smallest_eigen.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "runtime/simd.h"

namespace meshflow {
namespace {

// Below this difference of the two smallest eigenvalues (the matrix scaled to a largest entry
// of 1) the cubic's smallest root is too coarse for one Rayleigh refinement (measured: the
// vector within 5e-16 / gap rad of Eigen's iterative solver down to this gap).
constexpr double kMinGap = 1e-5;
// Newton steps onto the smallest root at most.
constexpr int kMaxSteps = 40;

SmallestEigen by_compute_direct(const Eigen::Matrix3d& a) {
  const Eigen::Matrix3d full = a.selfadjointView<Eigen::Upper>();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(full);
  return {solver.eigenvalues(), solver.eigenvectors().col(0).normalized(), false};
}

}  // namespace

MESHFLOW_AVX2_CLONES SmallestEigen smallest_eigen(const Eigen::Matrix3d& a) {
  const double scale = std::max({std::abs(a(0, 0)), std::abs(a(0, 1)), std::abs(a(0, 2)),
                                 std::abs(a(1, 1)), std::abs(a(1, 2)), std::abs(a(2, 2))});
  if (!(scale > 0.0) || !std::isfinite(scale)) return by_compute_direct(a);
  const double inv = 1.0 / scale;
  const double b01 = a(0, 1) * inv, b02 = a(0, 2) * inv, b12 = a(1, 2) * inv;
  const double b00 = a(0, 0) * inv, b11 = a(1, 1) * inv, b22 = a(2, 2) * inv;
  // C = B - m I is traceless: det(C - mu I) = -mu^3 + 3 p2 mu + det(C), roots within +-2 p.
  const double m = (b00 + b11 + b22) / 3.0;
  const double c00 = b00 - m, c11 = b11 - m, c22 = b22 - m;
  const double p2 =
      (c00 * c00 + c11 * c11 + c22 * c22 + 2.0 * (b01 * b01 + b02 * b02 + b12 * b12)) / 6.0;
  if (!(p2 > kMinGap * kMinGap)) return by_compute_direct(a);  // a multiple of I, nearly
  const double p = std::sqrt(p2);
  const double det =
      c00 * (c11 * c22 - b12 * b12) - b01 * (b01 * c22 - b12 * b02) + b02 * (b01 * b12 - c11 * b02);
  // mu0 by Newton from the bound -2 p: g(mu) = det + mu (3 p2 - mu^2) is convex and decreasing
  // left of mu0 (mu0 <= -p < 0), so the steps rise monotonically onto it; converged when a step
  // is below 1e-12 p (the next would be below 1e-24 / gap). Near a double root mu0 = mu1 = -p
  // they slow to halving: no convergence in kMaxSteps is a gap far below kMinGap.
  double low = -2.0 * p;
  bool converged = false;
  for (int step = 0; step < kMaxSteps && !converged; ++step) {
    const double slope = 3.0 * (p2 - low * low);
    if (!(slope < 0.0)) break;
    const double move = (det + low * (3.0 * p2 - low * low)) / slope;
    low -= move;
    converged = std::abs(move) <= 1e-12 * p;
  }
  if (!converged) return by_compute_direct(a);
  // The other two roots: g(mu) = -(mu - mu0) (mu^2 + mu0 mu + mu0^2 - 3 p2).
  const double half_split = 0.5 * std::sqrt(std::max(0.0, 12.0 * p2 - 3.0 * low * low));
  const double middle = -0.5 * low - half_split, top = -0.5 * low + half_split;
  const double gap = middle - low;
  if (!(gap > kMinGap)) return by_compute_direct(a);
  // The rows of C - mu0 I span the plane of the other two eigenvectors: their cross products
  // are multiples of the wanted one (the adjugate's columns); the longest is the best. mu0's
  // rounding (about 1e-16 / gap) tilts it by that over the gap (1e-12 rad at gap 1e-2: enough
  // to change a float normal's bits now and then); the Rayleigh quotient of the vector found
  // gives mu0 to rounding (its error is the square of the tilt's) and a second pass the vector
  // to about 1e-16 / gap, as Eigen's iterative solver.
  Eigen::Vector3d x;
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1) {
      low = x.dot(Eigen::Vector3d(c00 * x.x() + b01 * x.y() + b02 * x.z(),
                                  b01 * x.x() + c11 * x.y() + b12 * x.z(),
                                  b02 * x.x() + b12 * x.y() + c22 * x.z()));
    }
    const Eigen::Vector3d r0(c00 - low, b01, b02), r1(b01, c11 - low, b12), r2(b02, b12, c22 - low);
    const Eigen::Vector3d x01 = r0.cross(r1), x02 = r0.cross(r2), x12 = r1.cross(r2);
    const double n01 = x01.squaredNorm(), n02 = x02.squaredNorm(), n12 = x12.squaredNorm();
    const double n = std::max({n01, n02, n12});
    if (!(n > 0.0) || !std::isfinite(n)) return by_compute_direct(a);
    x = (n01 >= n02 ? (n01 >= n12 ? x01 : x12) : (n02 >= n12 ? x02 : x12)) / std::sqrt(n);
  }
  SmallestEigen out;
  out.values = Eigen::Vector3d(m + low, m + middle, m + top) * scale;
  out.vector = x;
  return out;
}

}  // namespace meshflow
