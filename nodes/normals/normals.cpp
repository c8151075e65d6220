#include "nodes/normals/normals.h"

#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <algorithm>

namespace meshflow {
namespace {

struct LocalFrame {
  Eigen::Vector3d mean;
  Eigen::Matrix3d axes;  // columns: principal axes, smallest variance first
};

LocalFrame principal_frame(const std::vector<Eigen::Vector3f>& pts, std::size_t n) {
  LocalFrame f{Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity()};
  for (std::size_t i = 0; i < n; ++i) f.mean += pts[i].cast<double>();
  f.mean /= static_cast<double>(n);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d d = pts[i].cast<double>() - f.mean;
    cov.noalias() += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(cov);
  f.axes = solver.eigenvectors();
  return f;
}

// Thesis criterion: the neighbourhood's bounding box must not be degenerate. The box is taken
// in the neighbours' principal frame, so a sloped scan line is recognised as a line.
bool box_well_shaped(const std::vector<Eigen::Vector3f>& pts, std::size_t n, const LocalFrame& f,
                     float ratio) {
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(1e300), hi = -lo;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d d = pts[i].cast<double>() - f.mean;
    const Eigen::Vector2d c(d.dot(f.axes.col(1)), d.dot(f.axes.col(2)));
    lo = lo.cwiseMin(c);
    hi = hi.cwiseMax(c);
  }
  const Eigen::Vector2d extent = hi - lo;  // (middle axis, major axis)
  return extent.x() >= ratio * extent.y();
}

}  // namespace

Eigen::Vector3f fit_plane_normal(const std::vector<Eigen::Vector3f>& points) {
  if (points.size() < 3) return Eigen::Vector3f::Zero();
  return principal_frame(points, points.size()).axes.col(0).normalized().cast<float>();
}

std::vector<Eigen::Vector3f> estimate_normals(const PointCloud& cloud, const SpatialIndex& index,
                                              const NormalsConfig& config) {
  const std::size_t n = cloud.size();
  const std::size_t kn = static_cast<std::size_t>(std::max(config.kn, 3));
  const std::size_t ki = static_cast<std::size_t>(std::max(config.ki, 1));
  const std::size_t table_k = std::max(kn, ki);
  const Eigen::Vector3f viewpoint =
      config.orientation == NormalOrientation::kTowardSensor && cloud.has_sensor_origin
          ? cloud.sensor_origin
          : config.viewpoint;
  const float sign = config.orientation == NormalOrientation::kAwayFromViewpoint ? -1.0f : 1.0f;

  // Pass 1: neighbour table (reused by interpolation) and oriented plane normals.
  std::vector<std::uint32_t> table(n * table_k);
  std::vector<std::uint32_t> found_count(n);
  std::vector<Eigen::Vector3f> normals(n);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, n, 512), [&](const tbb::blocked_range<std::size_t>& r) {
        std::vector<std::uint32_t> idx(static_cast<std::size_t>(
            std::max<int>(config.adaptive_max_k, static_cast<int>(table_k))));
        std::vector<float> d2(idx.size());
        std::vector<Eigen::Vector3f> pts(idx.size());
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const Eigen::Vector3f& p = cloud.positions[i];
          std::size_t found = index.knn(p, table_k, idx.data(), d2.data());
          std::copy(idx.begin(), idx.begin() + static_cast<std::ptrdiff_t>(found),
                    table.begin() + static_cast<std::ptrdiff_t>(i * table_k));
          found_count[i] = static_cast<std::uint32_t>(found);
          std::size_t k = std::min(kn, found);
          for (std::size_t j = 0; j < k; ++j) pts[j] = cloud.positions[idx[j]];
          Eigen::Vector3f normal = Eigen::Vector3f::Zero();
          if (k >= 3) {
            LocalFrame frame = principal_frame(pts, k);
            while (config.adaptive_k && !box_well_shaped(pts, k, frame, config.adaptive_ratio) &&
                   k < static_cast<std::size_t>(config.adaptive_max_k) && k < index.size()) {
              const std::size_t want =
                  std::min<std::size_t>(2 * k, static_cast<std::size_t>(config.adaptive_max_k));
              k = index.knn(p, want, idx.data(), d2.data());
              for (std::size_t j = 0; j < k; ++j) pts[j] = cloud.positions[idx[j]];
              frame = principal_frame(pts, k);
            }
            normal = frame.axes.col(0).normalized().cast<float>();
          }
          const Eigen::Vector3f to_view = viewpoint - p;
          if (normal.isZero()) normal = to_view.normalized();
          if (sign * normal.dot(to_view) < 0.0f) normal = -normal;
          normals[i] = normal;
        }
      });
  if (ki <= 1) return normals;

  // Pass 2: interpolation over the ki nearest neighbours' oriented normals.
  std::vector<Eigen::Vector3f> smoothed(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        Eigen::Vector3f sum = Eigen::Vector3f::Zero();
                        const std::size_t k = std::min<std::size_t>(ki, found_count[i]);
                        for (std::size_t j = 0; j < k; ++j) sum += normals[table[i * table_k + j]];
                        const float len = sum.norm();
                        smoothed[i] = len > 0.0f ? Eigen::Vector3f(sum / len) : normals[i];
                      }
                    });
  return smoothed;
}

}  // namespace meshflow
