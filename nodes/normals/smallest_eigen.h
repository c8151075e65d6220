#pragma once
// The eigenvector of a 3 x 3 covariance's smallest eigenvalue in closed form: all a plane fit
// needs, at about half the work of Eigen's SelfAdjointEigenSolver::computeDirect (which finds
// all three eigenvectors).

#include <Eigen/Core>

namespace meshflow {

/// A symmetric 3 x 3 matrix's eigenvalues and the eigenvector of the smallest.
struct SmallestEigen {
  Eigen::Vector3d values;   ///< ascending
  Eigen::Vector3d vector;   ///< unit eigenvector of values[0], either sign
  bool closed_form = true;  ///< false: the ill-conditioned case, answered by computeDirect
};

/// Eigen-decomposition of the symmetric matrix `a` (finite; only its upper triangle is read)
/// for its smallest eigenpair. On `a` scaled to a largest entry of 1: the smallest root of the
/// characteristic cubic by Newton steps from a lower bound (the other two from the remaining
/// quadratic); its eigenvector the longest cross product of two rows of (a - values[0] I),
/// found again at that vector's Rayleigh quotient. When that is ill-conditioned (the two smallest
/// eigenvalues within 1e-5 of the largest entry: points on a line, a ball, one point; a zero or
/// non-finite matrix) Eigen's computeDirect answers instead (closed_form = false). Accuracy
/// otherwise (measured against Eigen's iterative solver): the vector within about 1e-15 / gap rad
/// (gap: the two smallest eigenvalues' difference over the largest entry), values[0] to about 1e-14
/// of the largest entry, values[1] and values[2] to 1e-8 of it where they nearly coincide.
/// Thread-safe, O(1).
SmallestEigen smallest_eigen(const Eigen::Matrix3d& a);

}  // namespace meshflow
