#include "nodes/optimize/cleanup/mesh_cleanup.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <numeric>

#include "fixtures/mesh_fixtures.h"
#include "nodes/optimize/cleanup/manifold_repair.h"
#include "test_support.h"

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

TEST(MeshCleanup, PiecesTheSplitSeparatesAreRemovedWhenSmall) {
  // A 6 x 6 grid (50 triangles) and one triangle hanging on its corner vertex 0: one component
  // by shared vertices until the split gives the triangle a vertex of its own.
  TriangleMesh m = test::grid_mesh(6);
  const auto b = static_cast<std::uint32_t>(m.vertices.size());
  m.vertices.insert(m.vertices.end(), {{-1, 0, 0.5f}, {0, -1, 0.5f}});
  m.triangles.push_back({0, b, b + 1});
  CleanupConfig config;
  config.min_component_triangles = 20;
  CleanupReport report;
  const TriangleMesh out = clean_mesh(m, config, &report);
  EXPECT_EQ(report.split_vertices, 1u);
  EXPECT_EQ(report.removed_components, 1u);
  EXPECT_EQ(report.removed_component_triangles, 1u);
  EXPECT_EQ(out.triangles.size(), 50u);
  EXPECT_EQ(out.vertices.size(), 36u) << "the split copy and the hanging corners are gone";
  EXPECT_EQ(test::half_edge_problem(out), "");
}

// The definitions, brute force. A later copy of a face (same corners in any order) is a
// duplicate of the first.
std::vector<bool> duplicates_oracle(const std::vector<Triangle>& tris) {
  std::vector<bool> dup(tris.size(), false);
  for (std::size_t j = 0; j < tris.size(); ++j) {
    Triangle b = tris[j];
    std::sort(b.begin(), b.end());
    for (std::size_t i = 0; i < j && !dup[j]; ++i) {
      Triangle a = tris[i];
      std::sort(a.begin(), a.end());
      dup[j] = a == b;
    }
  }
  return dup;
}

// The triangles around v fall into fans, joined where they share a corner other than v; every
// fan but the one holding v's lowest triangle gets a copy of v, appended in vertex order and then
// in order of the fans' lowest triangles.
TriangleMesh split_oracle(const TriangleMesh& m) {
  TriangleMesh out = m;
  for (std::uint32_t v = 0; v < m.vertices.size(); ++v) {
    std::vector<std::uint32_t> around;
    for (std::uint32_t t = 0; t < m.triangles.size(); ++t)
      for (std::uint32_t x : m.triangles[t])
        if (x == v) around.push_back(t);  // once per repetition, as vertex_triangles
    std::vector<std::uint32_t> fan(around.size());
    std::iota(fan.begin(), fan.end(), 0u);
    for (bool joined = true; joined;) {  // smallest slot of each fan, by relaxation
      joined = false;
      for (std::size_t i = 0; i < around.size(); ++i)
        for (std::size_t j = 0; j < around.size(); ++j) {
          bool shared = false;
          for (std::uint32_t x : m.triangles[around[i]])
            for (std::uint32_t y : m.triangles[around[j]]) shared |= x != v && x == y;
          if (shared && fan[j] < fan[i]) {
            fan[i] = fan[j];
            joined = true;
          }
        }
    }
    std::vector<std::uint32_t> copy_of_slot(around.size(), v);
    for (std::size_t i = 0; i < around.size(); ++i) {
      if (fan[i] != i || fan[i] == fan[0]) continue;  // not a fan's first slot, or v's own fan
      copy_of_slot[i] = static_cast<std::uint32_t>(out.vertices.size());
      out.vertices.push_back(m.vertices[v]);
    }
    for (std::size_t i = 0; i < around.size(); ++i)
      for (std::uint32_t& corner : out.triangles[around[i]])
        if (corner == v) corner = copy_of_slot[fan[i]];
  }
  return out;
}

TEST(MeshCleanup, DuplicatesAndNonManifoldSplitsMatchTheDefinitionsOnMessyMeshes) {
  for (std::uint32_t seed : {1u, 2u, 3u}) {
    const TriangleMesh m = test::messy_mesh(12, seed);
    CleanupConfig config;
    config.min_component_triangles = 0;
    config.split_non_manifold_vertices = false;
    const std::vector<bool> dup = duplicates_oracle(m.triangles);
    for (int threads : {1, 2}) {
      CleanupReport report;
      const TriangleMesh out =
          test::with_threads(threads, [&] { return clean_mesh(m, config, &report); });
      std::vector<Triangle> kept;  // no triangle of the grid is degenerate; junk may be
      std::size_t duplicates = 0;
      for (std::size_t t = 0; t < m.triangles.size(); ++t) {
        const Triangle& tri = m.triangles[t];
        const bool degenerate = tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] ||
                                !((m.vertices[tri[1]] - m.vertices[tri[0]])
                                      .cross(m.vertices[tri[2]] - m.vertices[tri[0]])
                                      .squaredNorm() > 0.0f);
        if (!degenerate && dup[t]) ++duplicates;
        if (!degenerate && !dup[t]) kept.push_back(tri);
      }
      EXPECT_EQ(report.duplicate_triangles, duplicates) << "seed " << seed;
      EXPECT_EQ(out.triangles, compact_vertices(m, kept).triangles) << "seed " << seed;

      TriangleMesh split = m;
      const std::size_t added =
          test::with_threads(threads, [&] { return split_non_manifold_vertices(split); });
      const TriangleMesh expected = split_oracle(m);
      EXPECT_EQ(added, expected.vertices.size() - m.vertices.size()) << "seed " << seed;
      EXPECT_GT(added, 0u) << "seed " << seed;  // the junk made some
      EXPECT_EQ(split.vertices, expected.vertices) << "seed " << seed;
      EXPECT_EQ(split.triangles, expected.triangles) << "seed " << seed;
    }
  }
}

}  // namespace
}  // namespace meshflow
