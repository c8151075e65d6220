#include "nodes/eval/completeness.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "nodes/search/mesh_distance_index.h"
#include "runtime/error.h"

namespace meshflow {
namespace {

constexpr float kSampleU = 0.3f, kSampleV = 0.6f;

// Farthest vertex of `from` from the surface of `to`.
double farthest_vertex(const TriangleMesh& from, const TriangleMesh& to) {
  const MeshDistanceIndex index(to);
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, from.vertices.size()), 0.0,
      [&](const tbb::blocked_range<std::size_t>& r, double worst) {
        for (std::size_t i = r.begin(); i < r.end(); ++i)
          worst = std::max(worst, static_cast<double>(index.closest(from.vertices[i]).distance));
        return worst;
      },
      [](double x, double y) { return std::max(x, y); });
}

}  // namespace

std::vector<std::uint8_t> ray_coverage(const TriangleMesh& mesh, const PinholeIntrinsics& k,
                                       const Eigen::Isometry3f& T_world_camera) {
  const int w = k.width, h = k.height;
  std::vector<std::uint8_t> covered(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), 0);
  const Eigen::Isometry3f T_camera_world = T_world_camera.inverse();
  // Image-plane positions of the vertices (NaN behind the camera).
  std::vector<Eigen::Vector2f> image(mesh.vertices.size());
  tbb::parallel_for(std::size_t{0}, mesh.vertices.size(), [&](std::size_t i) {
    const Eigen::Vector3f c = T_camera_world * mesh.vertices[i];
    image[i] = c.z() > 0.0f
                   ? Eigen::Vector2f(c.x() / c.z() * k.fx + k.cx, c.y() / c.z() * k.fy + k.cy)
                   : Eigen::Vector2f::Constant(std::nanf(""));
  });
  // Rows are independent: each row task rasterises every triangle's span on its row.
  // Triangles are first bucketed by the rows they touch.
  std::vector<std::vector<std::uint32_t>> rows(static_cast<std::size_t>(h));
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const Eigen::Vector2f &a = image[tri[0]], &b = image[tri[1]], &c = image[tri[2]];
    if (!(a.allFinite() && b.allFinite() && c.allFinite())) continue;
    const float lo = std::min({a.y(), b.y(), c.y()}) - kSampleV;
    const float hi = std::max({a.y(), b.y(), c.y()}) - kSampleV;
    const int v0 = std::max(0, static_cast<int>(std::ceil(lo)));
    const int v1 = std::min(h - 1, static_cast<int>(std::floor(hi)));
    for (int v = v0; v <= v1; ++v) rows[static_cast<std::size_t>(v)].push_back(t);
  }
  tbb::parallel_for(0, h, [&](int v) {
    const float y = static_cast<float>(v) + kSampleV;
    for (std::uint32_t t : rows[static_cast<std::size_t>(v)]) {
      const auto& tri = mesh.triangles[t];
      const Eigen::Vector2f &a = image[tri[0]], &b = image[tri[1]], &c = image[tri[2]];
      const float lo = std::min({a.x(), b.x(), c.x()}) - kSampleU;
      const float hi = std::max({a.x(), b.x(), c.x()}) - kSampleU;
      const int u0 = std::max(0, static_cast<int>(std::ceil(lo)));
      const int u1 = std::min(w - 1, static_cast<int>(std::floor(hi)));
      auto edge = [](const Eigen::Vector2f& p, const Eigen::Vector2f& q, float x, float yy) {
        return (q.x() - p.x()) * (yy - p.y()) - (q.y() - p.y()) * (x - p.x());
      };
      for (int u = u0; u <= u1; ++u) {
        const float x = static_cast<float>(u) + kSampleU;
        const float e0 = edge(a, b, x, y), e1 = edge(b, c, x, y), e2 = edge(c, a, x, y);
        const bool inside = (e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0);
        if (inside)
          covered[static_cast<std::size_t>(v) * static_cast<std::size_t>(w) +
                  static_cast<std::size_t>(u)] = 1;
      }
    }
  });
  return covered;
}

Completeness completeness(const TriangleMesh& mesh, const TriangleMesh& reference,
                          const PinholeIntrinsics& intrinsics,
                          const Eigen::Isometry3f& T_world_camera) {
  const auto m = ray_coverage(mesh, intrinsics, T_world_camera);
  const auto r = ray_coverage(reference, intrinsics, T_world_camera);
  Completeness c;
  for (std::size_t i = 0; i < m.size(); ++i) {
    c.mesh_hits += m[i];
    c.reference_hits += r[i];
    c.shared_hits += m[i] & r[i];
  }
  return c;
}

double hausdorff_distance(const TriangleMesh& a, const TriangleMesh& b) {
  if (a.triangles.empty() || b.triangles.empty())
    throw Error("hausdorff", "mesh", "both meshes need triangles");
  return std::max(farthest_vertex(a, b), farthest_vertex(b, a));
}

}  // namespace meshflow
