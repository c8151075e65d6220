#include "nodes/optimize/planar/plane_intersections.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "fixtures/mesh_fixtures.h"
#include "nodes/optimize/optimize_mesh.h"

namespace meshflow {
namespace {

// Distance of p from the unit cube's nearest edge (two coordinates at 0 or 1).
float cube_edge_distance(const Eigen::Vector3f& p) {
  float best = std::numeric_limits<float>::infinity();
  for (int along = 0; along < 3; ++along)
    for (float a : {0.0f, 1.0f})
      for (float b : {0.0f, 1.0f}) {
        const int i = (along + 1) % 3, j = (along + 2) % 3;
        const float t = std::clamp(p[along], 0.0f, 1.0f);
        best = std::min(best, std::hypot(p[along] - t, std::hypot(p[i] - a, p[j] - b)));
      }
  return best;
}

// The cube (n x n squares a face) with every vertex on an edge or a corner moved off it by up to
// 0.2 of a square, in a fixed pseudo-random direction; the other vertices exact.
TriangleMesh cube_with_stray_edges(int n) {
  TriangleMesh m = test::tessellated_cube(n);
  for (std::size_t v = 0; v < m.vertices.size(); ++v) {
    if (cube_edge_distance(m.vertices[v]) > 0.0f) continue;
    Eigen::Vector3f offset;
    for (int k = 0; k < 3; ++k) {
      const double hash = std::sin(12.9898 * static_cast<double>(3 * v + k) + 78.233) * 43758.5453;
      offset[k] = static_cast<float>(2.0 * (hash - std::floor(hash)) - 1.0);
    }
    m.vertices[v] += 0.2f / static_cast<float>(n) * offset / std::sqrt(3.0f);
  }
  return m;
}

double mean_edge_distance(const TriangleMesh& m, const MeshFeatures& f, float& worst) {
  double sum = 0.0;
  std::size_t count = 0;
  worst = 0.0f;
  for (std::uint32_t v = 0; v < m.vertices.size(); ++v) {
    if (f.vertex_kind[v] == MeshFeatures::VertexKind::kFree) continue;
    const float d = cube_edge_distance(m.vertices[v]);
    sum += static_cast<double>(d);
    worst = std::max(worst, d);
    ++count;
  }
  return count > 0 ? sum / static_cast<double>(count) : 0.0;
}

TEST(PlaneIntersections, StrayEdgeVerticesGoBackOntoTheCubesEdgesAndCorners) {
  const int n = 12;
  const TriangleMesh stray = cube_with_stray_edges(n);
  const MeshFeatures f = detect_features(stray);
  ASSERT_EQ(f.edges.size(), 12u * n);
  ASSERT_EQ(f.count(MeshFeatures::VertexKind::kCorner), 8u);
  float worst_before = 0.0f;
  const double before = mean_edge_distance(stray, f, worst_before);
  HalfEdgeMesh h(stray);
  const PlanarSegmentation s = grow_planar_regions(h);
  ASSERT_EQ(s.regions.size(), 6u);
  const PlaneIntersectionReport r = project_onto_plane_intersections(h, s, f);
  EXPECT_EQ(r.to_line, 12u * (n - 1));
  EXPECT_EQ(r.to_corner, 8u);
  EXPECT_EQ(r.refused, 0u);
  TriangleMesh moved = stray;
  for (std::uint32_t v = 0; v < moved.vertices.size(); ++v) moved.vertices[v] = h.position(v);
  float worst_after = 0.0f;
  const double after = mean_edge_distance(moved, f, worst_after);
  std::printf("[ planes ] cube edge vertices off the edges: mean %.2e (max %.2e) -> %.2e (%.2e)\n",
              before, static_cast<double>(worst_before), after, static_cast<double>(worst_after));
  // The region planes are fitted to the stray vertices too, so they are a little off (measured:
  // 7.5e-3 -> 7.8e-4 mean, 1.3e-2 -> 1.5e-3 largest): the vertices land within a sixth of
  // where they were.
  EXPECT_LT(after, 0.15 * before);
  EXPECT_LT(worst_after, 0.15f * worst_before);
  // Along its line a vertex keeps its place: no two vertices of an edge come closer than
  // 0.5 of a square.
  for (const auto& e : f.edges)
    EXPECT_GT((moved.vertices[e[0]] - moved.vertices[e[1]]).norm(), 0.5f / n);
}

TEST(PlaneIntersections, ThePlanesStepMovesFeatureVerticesOnlyWithFeatures) {
  const int n = 12;
  const TriangleMesh stray = cube_with_stray_edges(n);
  const MeshFeatures f = detect_features(stray);
  OptimizeConfig config;
  config.steps = {OptimizeStep::kPlanes};
  float worst = 0.0f;
  const double before = mean_edge_distance(stray, f, worst);
  const double with = mean_edge_distance(optimize_mesh(stray, config), f, worst);
  config.feature_angle_deg = 180.0f;
  const double without = mean_edge_distance(optimize_mesh(stray, config), f, worst);
  EXPECT_LT(with, 0.15 * before);
  EXPECT_NEAR(without, before, 1e-9);  // a vertex of two regions stays where it is
}

TEST(PlaneIntersections, FarMovesAreRefused) {
  const int n = 12;
  const TriangleMesh stray = cube_with_stray_edges(n);
  const MeshFeatures f = detect_features(stray);
  HalfEdgeMesh h(stray);
  const PlanarSegmentation s = grow_planar_regions(h);
  const PlaneIntersectionReport r = project_onto_plane_intersections(h, s, f, 1e-6f);
  EXPECT_EQ(r.to_line + r.to_corner, 0u);
  EXPECT_EQ(r.refused, 12u * (n - 1) + 8u);
  for (std::uint32_t v = 0; v < stray.vertices.size(); ++v)
    EXPECT_EQ(h.position(v), stray.vertices[v]);
}

}  // namespace
}  // namespace meshflow
