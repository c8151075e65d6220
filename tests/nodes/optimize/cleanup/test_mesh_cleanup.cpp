#include "nodes/optimize/cleanup/mesh_cleanup.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <map>
#include <numeric>

#include "fixtures/mesh_fixtures.h"
#include "nodes/optimize/cleanup/hole_filling.h"
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
  config.non_manifold_vertices = NonManifoldVertexRepair::kSplit;
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
  config.non_manifold_vertices = NonManifoldVertexRepair::kNone;
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
  config.non_manifold_vertices = NonManifoldVertexRepair::kSplit;
  CleanupReport report;
  const TriangleMesh out = clean_mesh(m, config, &report);
  EXPECT_EQ(report.split_vertices, 1u);
  EXPECT_EQ(report.removed_components, 1u);
  EXPECT_EQ(report.removed_component_triangles, 1u);
  EXPECT_EQ(out.triangles.size(), 50u);
  EXPECT_EQ(out.vertices.size(), 36u) << "the split copy and the hanging corners are gone";
  EXPECT_EQ(test::half_edge_problem(out), "");
  // By default the hanging triangle is the smaller fan at vertex 0 and goes the same way.
  CleanupReport fans;
  const TriangleMesh removed = clean_mesh(m, CleanupConfig{}, &fans);
  EXPECT_EQ(fans.non_manifold_vertices, 1u);
  EXPECT_EQ(fans.removed_fan_triangles, 1u);
  EXPECT_EQ(fans.split_vertices, 0u);
  EXPECT_EQ(removed.triangles, out.triangles);
  EXPECT_EQ(removed.vertices, out.vertices);
}

// Two 5 x 5 grids (32 triangles each, above the component limit) meeting corner to corner at
// one vertex, as two pieces of a scan's border do (a bow tie), and a third sheet touching the
// first grid's middle (a closed fan meeting an open one). Splitting left two coincident copies
// there, which a reader that welds vertices on load (Open3D's OBJ / glTF readers, trimesh)
// joins into the non-manifold vertex again; the clean step now removes the smaller fans.
TEST(MeshCleanup, NoCoincidentVerticesAfterNonManifoldVerticesAreRepaired) {
  TriangleMesh m = test::grid_mesh(5);
  TriangleMesh other = test::grid_mesh(5);  // its vertex 0 on the first grid's last vertex 24
  const auto offset = static_cast<std::uint32_t>(m.vertices.size());
  for (const Eigen::Vector3f& p : other.vertices)
    m.vertices.push_back(p + Eigen::Vector3f(4.0f, 4.0f, 0.0f));
  for (Triangle t : other.triangles) {
    for (std::uint32_t& c : t) c = c == 0 ? 24u : c + offset;
    m.triangles.push_back(t);
  }
  const TriangleMesh input = compact_vertices(m, m.triangles);  // other's vertex 0 dropped
  const test::WeldedTopology before = test::welded_topology(input);
  EXPECT_EQ(before.coincident_pairs, 0u);
  EXPECT_EQ(before.non_manifold_vertices, 1u);

  CleanupConfig split;
  split.non_manifold_vertices = NonManifoldVertexRepair::kSplit;
  const test::WeldedTopology after_split = test::welded_topology(clean_mesh(input, split));
  EXPECT_EQ(after_split.coincident_pairs, 1u) << "what the split left";
  EXPECT_EQ(after_split.non_manifold_vertices, 1u);

  for (int threads : {1, 2}) {
    CleanupReport report;
    const TriangleMesh out =
        test::with_threads(threads, [&] { return clean_mesh(input, CleanupConfig{}, &report); });
    const test::WeldedTopology after = test::welded_topology(out);
    EXPECT_EQ(after.coincident_pairs, 0u);
    EXPECT_EQ(after.non_manifold_vertices, 0u);
    EXPECT_EQ(after.non_manifold_edges, 0u);
    EXPECT_EQ(report.non_manifold_vertices, 1u);
    // Vertex 24 holds one triangle of each grid's corner cell or two; the first grid's
    // (lower triangle indices) stays on a tie.
    EXPECT_GE(report.removed_fan_triangles, 1u);
    EXPECT_LE(report.removed_fan_triangles, 2u);
    EXPECT_EQ(out.triangles.size(), input.triangles.size() - report.removed_fan_triangles);
    EXPECT_EQ(std::vector<Triangle>(out.triangles.begin(), out.triangles.begin() + 32),
              test::grid_mesh(5).triangles)
        << "the first grid keeps every triangle";
    EXPECT_EQ(test::half_edge_problem(out), "");
  }
}

// A closed sphere of radius 1 around `centre`: an octahedron (vertices on the axes) with each
// face subdivided twice and the vertices pushed onto the sphere; 128 triangles, outward.
TriangleMesh sphere_mesh(const Eigen::Vector3f& centre) {
  TriangleMesh m;
  m.vertices = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                 {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (int level = 0; level < 2; ++level) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> middle;
    const auto mid = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      auto [it, fresh] = middle.emplace(key, static_cast<std::uint32_t>(m.vertices.size()));
      if (fresh) m.vertices.push_back((m.vertices[a] + m.vertices[b]).normalized());
      return it->second;
    };
    std::vector<Triangle> finer;
    for (const Triangle& t : m.triangles) {
      const std::uint32_t ab = mid(t[0], t[1]), bc = mid(t[1], t[2]), ca = mid(t[2], t[0]);
      finer.insert(finer.end(), {{t[0], ab, ca}, {ab, t[1], bc}, {ca, bc, t[2]}, {ab, bc, ca}});
    }
    m.triangles = std::move(finer);
  }
  for (Eigen::Vector3f& p : m.vertices) p += centre;
  return m;
}

// Two closed spheres touching at one vertex (the marching-cubes case: two closed sheets at one
// grid point). Removing the smaller fan opens a 4-edge hole in one of them, which the holes
// step closes: clean and holes (the default steps) give closed, manifold surfaces without
// coincident vertices, where the split gave a copy that welds back into the pinch.
TEST(MeshCleanup, ClosedSheetsTouchingAtAVertexComeOutClosed) {
  TriangleMesh m = sphere_mesh(Eigen::Vector3f::Zero());
  const TriangleMesh second = sphere_mesh(Eigen::Vector3f(2, 0, 0));  // its vertex 1 on vertex 0
  const auto offset = static_cast<std::uint32_t>(m.vertices.size());
  m.vertices.insert(m.vertices.end(), second.vertices.begin(), second.vertices.end());
  for (Triangle t : second.triangles) {
    for (std::uint32_t& c : t) c = c == 1 ? 0u : c + offset;
    m.triangles.push_back(t);
  }
  m = compact_vertices(m, m.triangles);
  ASSERT_EQ(test::welded_topology(m).non_manifold_vertices, 1u);

  CleanupConfig split;
  split.non_manifold_vertices = NonManifoldVertexRepair::kSplit;
  const TriangleMesh split_mesh = fill_holes(clean_mesh(m, split));
  EXPECT_EQ(test::welded_topology(split_mesh).coincident_pairs, 1u) << "what the split left";
  EXPECT_EQ(test::welded_topology(split_mesh).non_manifold_vertices, 1u);

  CleanupReport report;
  const TriangleMesh cleaned = clean_mesh(m, CleanupConfig{}, &report);
  EXPECT_EQ(report.non_manifold_vertices, 1u);
  EXPECT_EQ(report.removed_fan_triangles, 4u);  // a tie: the first sphere's fan stays
  EXPECT_EQ(edge_statistics(cleaned).boundary_edges, 4u);
  HoleFillingReport holes;
  const TriangleMesh out = fill_holes(cleaned, HoleFillingConfig{}, &holes);
  EXPECT_EQ(holes.filled, 1u);
  EXPECT_TRUE(edge_statistics(out).closed());
  const test::WeldedTopology after = test::welded_topology(out);
  EXPECT_EQ(after.coincident_pairs, 0u);
  EXPECT_EQ(after.non_manifold_vertices, 0u);
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
    config.non_manifold_vertices = NonManifoldVertexRepair::kNone;
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

// On meshes with junk (triangles joining random vertices: vertices with several fans, edges
// with three or more faces), the passes leave every vertex with one fan (the split oracle adds
// no copy), keep the other triangles in order, and do not depend on the thread count.
TEST(MeshCleanup, RemovingSmallerFansLeavesOneFanPerVertexOnMessyMeshes) {
  for (std::uint32_t seed : {1u, 2u, 3u}) {
    const TriangleMesh m = test::messy_mesh(12, seed);
    std::vector<Triangle> first;
    for (int threads : {1, 2}) {
      std::vector<Triangle> kept = m.triangles;
      FanRemovalCounts counts;
      test::with_threads(threads, [&] {
        remove_smaller_fans(kept, m.vertices.size(), &counts);
        return 0;
      });
      EXPECT_GT(counts.vertices, 0u) << "seed " << seed;
      EXPECT_EQ(counts.triangles, m.triangles.size() - kept.size()) << "seed " << seed;
      TriangleMesh repaired = m;
      repaired.triangles = kept;
      EXPECT_EQ(split_oracle(repaired).vertices.size(), m.vertices.size()) << "seed " << seed;
      std::size_t at = 0;  // kept is a subsequence of the input
      for (const Triangle& t : m.triangles) at += at < kept.size() && kept[at] == t;
      EXPECT_EQ(at, kept.size()) << "seed " << seed;
      if (threads == 1)
        first = kept;
      else
        EXPECT_EQ(kept, first) << "seed " << seed;
      std::printf(
          "[ cleanup ] messy mesh %u: %zu of %zu triangles removed at %zu vertices in %zu passes\n",
          seed, counts.triangles, m.triangles.size(), counts.vertices, counts.passes);
    }
  }
}

}  // namespace
}  // namespace meshflow
