#include "nodes/optimize/feature_snap.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

#include "runtime/vertex_triangles.h"

namespace meshflow {
namespace {

using SnapKind = MeshFeatures::VertexKind;

/// The two other corners of triangle t, which has v as a corner.
std::array<std::uint32_t, 2> snap_other_corners(const Triangle& t, std::uint32_t v) {
  for (int k = 0; k < 3; ++k)
    if (t[k] == v) return {t[(k + 1) % 3], t[(k + 2) % 3]};
  return {t[0], t[1]};
}

/// Per triangle around v (in around's order), the label of its side: triangles sharing an
/// edge v - w that is not sharp are on one side.
std::vector<std::size_t> snap_sides(const TriangleMesh& mesh, const VertexTriangles& around,
                                    const MeshFeatures& f, std::uint32_t v) {
  const std::uint32_t* fan = around.begin(v);
  const auto k = static_cast<std::size_t>(around.end(v) - fan);
  std::vector<std::size_t> side(k);
  std::iota(side.begin(), side.end(), std::size_t{0});
  for (std::size_t i = 0; i < k; ++i)
    for (std::size_t j = 0; j < i; ++j) {
      const auto a = snap_other_corners(mesh.triangles[fan[i]], v);
      const auto b = snap_other_corners(mesh.triangles[fan[j]], v);
      for (std::uint32_t w : a) {
        if ((w != b[0] && w != b[1]) || f.has_edge(v, w) || side[i] == side[j]) continue;
        const std::size_t from = side[i], to = side[j];
        for (std::size_t& s : side) s = s == from ? to : s;
      }
    }
  return side;
}

/// The free vertices within two rings of the triangles `fan` (around v) on their side.
std::vector<std::uint32_t> snap_side_vertices(const TriangleMesh& mesh,
                                              const VertexTriangles& around, const MeshFeatures& f,
                                              std::uint32_t v,
                                              const std::vector<std::uint32_t>& fan) {
  std::vector<std::uint32_t> found;
  for (std::uint32_t t : fan)
    for (std::uint32_t w : snap_other_corners(mesh.triangles[t], v))
      if (f.vertex_kind[w] == SnapKind::kFree &&
          std::find(found.begin(), found.end(), w) == found.end())
        found.push_back(w);
  const std::size_t first_ring = found.size();
  for (std::size_t i = 0; i < first_ring; ++i)  // a free vertex's faces are all on its side
    for (const std::uint32_t* t = around.begin(found[i]); t != around.end(found[i]); ++t)
      for (std::uint32_t w : mesh.triangles[*t])
        if (f.vertex_kind[w] == SnapKind::kFree &&
            std::find(found.begin(), found.end(), w) == found.end())
          found.push_back(w);
  return found;
}

// Rounds of the trimmed refit in snap_fit_plane (each keeps the points within 3 robust
// deviations of the last plane; converged when none is dropped).
constexpr int kSnapTrimRounds = 8;
// A vertex moves only farther than this many robust deviations of its sides from their planes:
// where the planes are known better than the vertex lies on them.
constexpr double kSnapSpreads = 3.0;

/// The least-squares plane of `points`, with its smallest two scatter eigenvalues (ascending):
/// false when fewer than 3 points.
bool snap_least_squares(const TriangleMesh& mesh, const std::vector<std::uint32_t>& points,
                        FeaturePlane& plane, Eigen::Vector2d& lambda) {
  if (points.size() < 3) return false;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (std::uint32_t p : points) centroid += mesh.vertices[p].cast<double>();
  centroid /= static_cast<double>(points.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (std::uint32_t p : points) {
    const Eigen::Vector3d d = mesh.vertices[p].cast<double>() - centroid;
    scatter += d * d.transpose();
  }
  scatter /= static_cast<double>(points.size());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(scatter);
  lambda = eigen.eigenvalues().head<2>();  // ascending
  plane.normal = eigen.eigenvectors().col(0);
  plane.offset = plane.normal.dot(centroid);
  return true;
}

/// 1.4826 x the median distance of `points` from `plane` (the standard deviation of Gaussian
/// noise about it; a few strays do not count).
double snap_robust_deviation(const TriangleMesh& mesh, const std::vector<std::uint32_t>& points,
                             const FeaturePlane& plane, std::vector<double>& distances) {
  distances.clear();
  for (std::uint32_t p : points)
    distances.push_back(std::abs(plane.normal.dot(mesh.vertices[p].cast<double>()) - plane.offset));
  std::vector<double> sorted = distances;
  const auto middle = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
  std::nth_element(sorted.begin(), middle, sorted.end());
  return 1.4826 * *middle;
}

/// The plane of `points` (at least 5 of them, spread in two directions): least squares,
/// refitted through the points within 3 robust deviations of it until none is dropped, so that
/// a few stray points (an extraction's misplaced vertex next to an edge, a vertex across a gap
/// in the feature line) do not tilt an exact side. `deviation`: the robust deviation of all the
/// points from it; false when that exceeds `flatness` (a curved or noisy side).
bool snap_fit_plane(const TriangleMesh& mesh, const std::vector<std::uint32_t>& points,
                    double flatness, FeaturePlane& plane, double& deviation) {
  if (points.size() < 5) return false;
  Eigen::Vector2d lambda;
  snap_least_squares(mesh, points, plane, lambda);
  std::vector<std::uint32_t> kept = points, trimmed;
  std::vector<double> distances;
  for (int round = 0; round < kSnapTrimRounds; ++round) {
    const double limit = 3.0 * snap_robust_deviation(mesh, kept, plane, distances);
    trimmed.clear();
    for (std::size_t i = 0; i < kept.size(); ++i)
      if (distances[i] <= limit) trimmed.push_back(kept[i]);
    if (trimmed.size() == kept.size() || trimmed.size() < 5) break;
    kept.swap(trimmed);
    snap_least_squares(mesh, kept, plane, lambda);
  }
  deviation = snap_robust_deviation(mesh, points, plane, distances);
  return deviation <= flatness && lambda[1] > 16.0 * lambda[0] && lambda[1] > 0.0;
}

/// Whether moving v to `to` keeps every face around it with area and within 90 degrees of its
/// orientation.
bool snap_keeps_faces(const TriangleMesh& mesh, const VertexTriangles& around, std::uint32_t v,
                      const Eigen::Vector3f& to) {
  for (const std::uint32_t* t = around.begin(v); t != around.end(v); ++t) {
    const auto [b, c] = snap_other_corners(mesh.triangles[*t], v);
    const Eigen::Vector3f& pb = mesh.vertices[b];
    const Eigen::Vector3f& pc = mesh.vertices[c];
    const Eigen::Vector3f before = (pb - mesh.vertices[v]).cross(pc - mesh.vertices[v]);
    const Eigen::Vector3f after = (pb - to).cross(pc - to);
    if (!has_area(to, pb, pc) || before.dot(after) <= 0.0f) return false;
  }
  return true;
}

}  // namespace

bool planes_meet(const std::vector<FeaturePlane>& planes) {
  const double min_sin = std::sin(20.0 * M_PI / 180.0);
  for (std::size_t i = 0; i < planes.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (planes[i].normal.cross(planes[j].normal).norm() > min_sin) return true;
  return false;
}

Eigen::Vector3d move_onto_planes(const Eigen::Vector3d& point,
                                 const std::vector<FeaturePlane>& planes) {
  constexpr double kSpan = 0.02;  // smallest eigenvalue of the normals' sum counted as a direction
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d residual = Eigen::Vector3d::Zero();
  for (const FeaturePlane& p : planes) {
    a += p.normal * p.normal.transpose();
    residual += (p.offset - p.normal.dot(point)) * p.normal;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(a);
  Eigen::Vector3d step = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k)
    if (eigen.eigenvalues()[k] > kSpan) {
      const Eigen::Vector3d u = eigen.eigenvectors().col(k);
      step += u * (u.dot(residual) / eigen.eigenvalues()[k]);
    }
  return step;
}

FeatureSnapReport snap_feature_vertices(TriangleMesh& mesh, const MeshFeatures& features,
                                        float max_move, float flatness) {
  FeatureSnapReport report;
  if (features.edges.empty()) return report;
  const VertexTriangles around = vertex_triangles(mesh);
  for (std::uint32_t v = 0; v < mesh.vertices.size(); ++v) {
    if (features.vertex_kind[v] == SnapKind::kFree) continue;
    ++report.feature_vertices;
    const std::vector<std::size_t> side = snap_sides(mesh, around, features, v);
    std::vector<FeaturePlane> planes;
    double spread = 0.0;  // the largest robust deviation of a side from its plane
    std::vector<std::uint8_t> done(side.size(), 0);
    for (std::size_t i = 0; i < side.size(); ++i) {
      if (done[i]) continue;
      std::vector<std::uint32_t> fan;
      for (std::size_t j = i; j < side.size(); ++j)
        if (side[j] == side[i]) fan.push_back(around.begin(v)[j]), done[j] = 1;
      FeaturePlane plane;
      double deviation = 0.0;
      if (snap_fit_plane(mesh, snap_side_vertices(mesh, around, features, v, fan), flatness, plane,
                         deviation)) {
        planes.push_back(plane);
        spread = std::max(spread, deviation);
      }
    }
    if (!planes_meet(planes)) continue;
    const Eigen::Vector3d here = mesh.vertices[v].cast<double>();
    const Eigen::Vector3d step = move_onto_planes(here, planes);
    const Eigen::Vector3f to = (here + step).cast<float>();
    const float move = (to - mesh.vertices[v]).norm();
    if (!to.allFinite() || move > max_move || move == 0.0f ||
        static_cast<double>(move) <= kSnapSpreads * spread ||
        !snap_keeps_faces(mesh, around, v, to))
      continue;
    mesh.vertices[v] = to;
    ++report.moved;
    report.largest_move = std::max(report.largest_move, move);
  }
  return report;
}

}  // namespace meshflow
