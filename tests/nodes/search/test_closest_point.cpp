#include "nodes/search/closest_point.h"

#include <gtest/gtest.h>

#include <random>

#include "nodes/search/mesh_distance_index.h"
#include "nodes/synthetic/shapes.h"
#include "test_support.h"

namespace meshflow {
namespace {

TEST(ClosestPoint, MatchesDenseSamplingOfTheTriangle) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3f a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)),
        c(u(rng), u(rng), u(rng)), p(2 * u(rng), 2 * u(rng), 2 * u(rng));
    const Eigen::Vector3f q = closest_point_on_triangle(p, a, b, c);
    float best = std::numeric_limits<float>::max();
    const int n = 200;
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        const Eigen::Vector3f s = a + (b - a) * (float(i) / n) + (c - a) * (float(j) / n);
        best = std::min(best, (s - p).norm());
      }
    EXPECT_LE((q - p).norm(), best + 1e-5f);
    EXPECT_GE((q - p).norm(), best - 0.02f);  // sampling resolution
  }
  // Degenerate (collinear) triangle: the nearest point of the segment.
  const Eigen::Vector3f q =
      closest_point_on_triangle({0.5f, 1.0f, 0.0f}, {0, 0, 0}, {1, 0, 0}, {2, 0, 0});
  EXPECT_NEAR((q - Eigen::Vector3f(0.5f, 0, 0)).norm(), 0.0f, 1e-6f);
}

TEST(MeshDistanceIndex, EqualsBruteForceNearAndFar) {
  const synthetic::Sphere sphere{{0.1f, 0.0f, -0.2f}, 0.6f};
  const TriangleMesh mesh = [&] {
    TriangleMesh m;
    const PointCloud pts = synthetic::sample_surface(sphere, 0.1f, 0.0f, 1);
    // A closed mesh is not needed: a triangle soup of nearby sample triples.
    for (std::size_t i = 0; i + 2 < pts.size(); i += 3) {
      const auto v = static_cast<std::uint32_t>(m.vertices.size());
      m.vertices.push_back(pts.positions[i]);
      m.vertices.push_back(pts.positions[i] + Eigen::Vector3f(0.05f, 0.0f, 0.01f));
      m.vertices.push_back(pts.positions[i] + Eigen::Vector3f(0.0f, 0.04f, -0.02f));
      m.triangles.push_back({v, v + 1, v + 2});
    }
    return m;
  }();
  const MeshDistanceIndex index(mesh);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-3.0f, 3.0f);
  for (int trial = 0; trial < 300; ++trial) {
    const float scale = trial < 150 ? 0.3f : 1.0f;  // near the surface, then far away
    const Eigen::Vector3f p(scale * u(rng), scale * u(rng), scale * u(rng));
    float brute = std::numeric_limits<float>::max();
    for (const Triangle& t : mesh.triangles)
      brute = std::min(brute, (closest_point_on_triangle(p, mesh.vertices[t[0]],
                                                         mesh.vertices[t[1]], mesh.vertices[t[2]]) -
                               p)
                                  .norm());
    EXPECT_FLOAT_EQ(index.closest(p).distance, brute);
  }
}

}  // namespace
}  // namespace meshflow
