#include "nodes/optimize/mesh_cleanup.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>

#include "mesh_fixtures.h"

namespace meshflow {
namespace {

TEST(MeshCleanup, RemovesDegenerateDuplicateAndSmallComponents) {
  TriangleMesh m;
  // Component A: a strip of 30 triangles. Component B: 2 triangles. Plus junk.
  for (int i = 0; i < 17; ++i) {
    m.vertices.emplace_back(static_cast<float>(i), 0.0f, 0.0f);
    m.vertices.emplace_back(static_cast<float>(i), 1.0f, 0.0f);
  }
  for (std::uint32_t i = 0; i < 15; ++i) {
    m.triangles.push_back({2 * i, 2 * i + 2, 2 * i + 1});
    m.triangles.push_back({2 * i + 1, 2 * i + 2, 2 * i + 3});
  }
  const auto b = static_cast<std::uint32_t>(m.vertices.size());
  m.vertices.insert(m.vertices.end(), {{0, 5, 0}, {1, 5, 0}, {0, 6, 0}, {1, 6, 0}});
  m.triangles.push_back({b, b + 1, b + 2});
  m.triangles.push_back({b + 1, b + 3, b + 2});
  m.triangles.push_back({0, 0, 1});           // repeated index
  m.vertices.emplace_back(2.0f, 0.0f, 0.0f);  // collinear with vertices 0 and 2
  m.triangles.push_back({0, 2, b + 4});       // zero area
  m.triangles.push_back({2, 0, 1});           // duplicate of triangle 0 (other rotation)
  m.vertices.emplace_back(9, 9, 9);           // unreferenced
  compute_vertex_normals(m);
  const auto nan_corner = static_cast<std::uint32_t>(m.vertices.size());
  m.vertices.emplace_back(std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f);
  m.vertices.emplace_back(std::numeric_limits<float>::infinity(), 1.0f, 0.0f);
  m.normals.resize(m.vertices.size(), Eigen::Vector3f::UnitZ());
  m.triangles.push_back({0, 2, nan_corner});      // no defined area
  m.triangles.push_back({0, nan_corner + 1, 2});  // no defined area

  CleanupReport report;
  const TriangleMesh out = clean_mesh(m, CleanupConfig{true, 20}, &report);
  EXPECT_EQ(report.degenerate_triangles, 4u);
  EXPECT_EQ(report.duplicate_triangles, 1u);
  EXPECT_EQ(report.removed_components, 1u);
  EXPECT_EQ(report.removed_component_triangles, 2u);
  EXPECT_EQ(out.triangles.size(), 30u);
  EXPECT_EQ(out.vertices.size(), 32u);
  EXPECT_EQ(out.normals.size(), out.vertices.size());
  EXPECT_EQ(out.triangles[0], (Triangle{0, 2, 1}));
  EXPECT_EQ(edge_statistics(out).non_manifold_edges, 0u);
}

TEST(MeshCleanup, KeepsEverythingWhenDisabled) {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}};
  const TriangleMesh out = clean_mesh(m, CleanupConfig{true, 0});
  EXPECT_EQ(out.triangles, m.triangles);
}

TEST(MeshCleanup, SplitsVerticesWhereTwoSheetsTouch) {
  // Two closed tetrahedra touching at vertex 0 (two fans there), and a bow tie of two
  // triangles at vertex 4.
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3},   // first tetrahedron
                 {0, 4, 5}, {0, 6, 4}, {0, 5, 6}, {4, 6, 5}};  // second, mirrored
  const std::size_t first_tetrahedron = m.vertices.size();
  m.vertices.insert(m.vertices.end(), {{5, 0, 0}, {6, 0, 0}, {5, 1, 0}, {4, 0, 0}, {4, -1, 0}});
  const auto b = static_cast<std::uint32_t>(first_tetrahedron);
  m.triangles.push_back({b, b + 1, b + 2});
  m.triangles.push_back({b, b + 3, b + 4});
  compute_vertex_normals(m);
  CleanupConfig config;
  config.min_component_triangles = 0;
  CleanupReport report;
  const TriangleMesh out = clean_mesh(m, config, &report);
  EXPECT_EQ(report.split_vertices, 2u);
  ASSERT_EQ(out.vertices.size(), m.vertices.size() + 2);
  EXPECT_EQ(out.vertices[m.vertices.size()], m.vertices[0]);  // the copy sits where it was
  EXPECT_EQ(out.normals.size(), out.vertices.size());
  for (std::size_t t = 0; t < 4; ++t) EXPECT_EQ(out.triangles[t], m.triangles[t]);  // kept 0
  for (std::size_t t = 4; t < 8; ++t)
    EXPECT_EQ(std::count(out.triangles[t].begin(), out.triangles[t].end(), 0u), 0);
  EXPECT_EQ(test::half_edge_problem(out), "");
  config.split_non_manifold_vertices = false;
  EXPECT_EQ(clean_mesh(m, config).vertices.size(), m.vertices.size());
}

}  // namespace
}  // namespace meshflow
