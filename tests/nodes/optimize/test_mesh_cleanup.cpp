#include "nodes/optimize/mesh_cleanup.h"

#include <gtest/gtest.h>

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

  CleanupReport report;
  const TriangleMesh out = clean_mesh(m, CleanupConfig{true, 20}, &report);
  EXPECT_EQ(report.degenerate_triangles, 2u);
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

}  // namespace
}  // namespace meshflow
