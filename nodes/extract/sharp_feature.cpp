#include "nodes/extract/sharp_feature.h"

#include <Eigen/Eigenvalues>
#include <cmath>

#include "runtime/angles.h"

namespace meshflow {
namespace {

// Minimiser of sum_i (n_i . (x - p_i))^2 keeping the `rank` largest eigen-directions of
// sum_i n_i n_i^T (the others stay at the centroid).
Eigen::Vector3f solve_qef(const Eigen::Vector3f* points, const Eigen::Vector3f* normals,
                          std::size_t count, int rank) {
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
  for (std::size_t i = 0; i < count; ++i) centroid += points[i];
  centroid /= static_cast<float>(count);
  Eigen::Matrix3f ata = Eigen::Matrix3f::Zero();
  Eigen::Vector3f atb = Eigen::Vector3f::Zero();
  for (std::size_t i = 0; i < count; ++i) {
    ata += normals[i] * normals[i].transpose();
    atb += normals[i] * normals[i].dot(points[i] - centroid);
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> eigen(ata);
  Eigen::Vector3f offset = Eigen::Vector3f::Zero();
  // Eigenvalues ascend: keep the last `rank`, and none below a relative floor.
  const float floor = 1e-3f * eigen.eigenvalues()[2];
  for (int k = 3 - rank; k < 3; ++k) {
    const float lambda = eigen.eigenvalues()[k];
    if (lambda <= floor) continue;
    const Eigen::Vector3f u = eigen.eigenvectors().col(k);
    offset += u * (u.dot(atb) / lambda);
  }
  return centroid + offset;
}

}  // namespace

FeaturePoint sharp_feature(const Eigen::Vector3f* points, const Eigen::Vector3f* normals,
                           std::size_t count, const Eigen::AlignedBox3f& cell,
                           const SharpFeatureConfig& config) {
  FeaturePoint out;
  if (count < 2) return out;
  // The two most different normals span the feature.
  float min_cos = 1.0f;
  std::size_t a = 0, b = 0;
  for (std::size_t i = 0; i < count; ++i) {
    for (std::size_t j = i + 1; j < count; ++j) {
      const float c = normals[i].dot(normals[j]);
      if (c < min_cos) {
        min_cos = c;
        a = i;
        b = j;
      }
    }
  }
  if (!(min_cos < std::cos(radians(config.edge_angle_deg)))) return out;
  const Eigen::Vector3f axis = normals[a].cross(normals[b]);
  if (!(axis.norm() > 1e-6f)) return out;  // opposite normals: a thin sheet, not a feature
  const Eigen::Vector3f direction = axis.normalized();
  float out_of_plane = 0.0f;
  for (std::size_t i = 0; i < count; ++i)
    out_of_plane = std::max(out_of_plane, std::abs(normals[i].dot(direction)));
  out.kind = out_of_plane > std::sin(radians(config.corner_angle_deg)) ? FeatureKind::kCorner
                                                                       : FeatureKind::kEdge;
  const Eigen::Vector3f x =
      solve_qef(points, normals, count, out.kind == FeatureKind::kCorner ? 3 : 2);
  const float slack = config.max_outside * cell.sizes().maxCoeff();
  if (!x.allFinite() || cell.exteriorDistance(x) > slack) return FeaturePoint{};
  out.position = x.cwiseMax(cell.min()).cwiseMin(cell.max());
  return out;
}

}  // namespace meshflow
