#include "runtime/triangle_mesh.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <map>
#include <random>

#include "runtime/face_normals.h"
#include "runtime/threads.h"
#include "runtime/vertex_triangles.h"
#include "test_support.h"

namespace meshflow {
namespace {

TEST(TriangleMesh, TetrahedronIsClosedAndConsistent) {
  const EdgeStatistics s = edge_statistics(test::tetrahedron());
  EXPECT_EQ(s.edges, 6u);
  EXPECT_TRUE(s.closed());
  EXPECT_EQ(s.inconsistent_edges, 0u);
}

TEST(TriangleMesh, DetectsBoundaryNonManifoldAndFlippedFaces) {
  TriangleMesh m = test::tetrahedron();
  m.triangles[3] = {1, 3, 2};  // flipped
  EXPECT_EQ(edge_statistics(m).inconsistent_edges, 3u);
  m.triangles.pop_back();
  EXPECT_EQ(edge_statistics(m).boundary_edges, 3u);
  TriangleMesh fan;
  fan.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  fan.triangles = {{0, 1, 2}, {0, 1, 3}, {0, 1, 4}};  // edge 0-1 has three faces
  EXPECT_EQ(edge_statistics(fan).non_manifold_edges, 1u);
}

// counted_face_normals() is face_normal() bit for bit, on random faces (coordinates of many
// magnitudes, slivers, faces without area or with a repeated corner, non-finite coordinates),
// for any face count (short last groups) and thread count; its fourth lane counts the faces with
// a normal.
TEST(TriangleMesh, CountedFaceNormalsAreFaceNormalBitForBit) {
  std::mt19937 random(59);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::uniform_int_distribution<int> exponent(-20, 20);
  TriangleMesh m;
  for (int i = 0; i < 3000; ++i)
    m.vertices.emplace_back(std::ldexp(unit(random), exponent(random)), unit(random),
                            unit(random) * 1e3f);
  m.vertices.emplace_back(std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f);
  m.vertices.emplace_back(std::numeric_limits<float>::infinity(), 1.0f, 0.0f);
  m.vertices.emplace_back(3e19f, 3e19f, 1.0f);  // squares overflow: length infinite
  const auto n = static_cast<std::uint32_t>(m.vertices.size());
  std::uniform_int_distribution<std::uint32_t> vertex(0, n - 1);
  for (int i = 0; i < 20000; ++i) {
    const std::uint32_t a = vertex(random), b = vertex(random), c = vertex(random);
    m.triangles.push_back({a, b, c});
    if (i % 7 == 0) m.triangles.push_back({a, a, c});  // no area
    if (i % 11 == 0) {                                 // a sliver: c just off the line a-b
      m.vertices.push_back(0.5f * (m.vertices[a] + m.vertices[b]) +
                           Eigen::Vector3f(1e-6f, 0.0f, 0.0f));
      m.triangles.push_back({a, b, static_cast<std::uint32_t>(m.vertices.size() - 1)});
    }
  }
  m.triangles.push_back({n - 3, 0, 1});
  m.triangles.push_back({n - 2, 0, 1});
  m.triangles.push_back({n - 1, n - 2, 0});
  m.triangles.push_back({n - 1, 0, 1});
  for (std::size_t count :
       {std::size_t{0}, std::size_t{5}, std::size_t{8}, std::size_t{13}, m.triangles.size()}) {
    TriangleMesh part = m;
    part.triangles.resize(count);
    for (int threads : {1, 2}) {
      ThreadLimit limit(threads);
      const std::vector<Eigen::Vector4f> normals = counted_face_normals(part);
      ASSERT_EQ(normals.size(), count);
      std::size_t with_normal = 0, mismatches = 0;
      for (std::size_t t = 0; t < count; ++t) {
        const Eigen::Vector3f expected = face_normal(part, part.triangles[t]);
        const Eigen::Vector3f got = normals[t].head<3>();
        mismatches += std::memcmp(expected.data(), got.data(), sizeof(float) * 3) != 0 ? 1 : 0;
        EXPECT_EQ(normals[t].w(), expected.squaredNorm() > 0.0f ? 1.0f : 0.0f) << t;
        with_normal += normals[t].w() != 0.0f ? 1 : 0;
      }
      EXPECT_EQ(mismatches, 0u) << count << " faces, " << threads << " threads";
      if (count == m.triangles.size()) {
        EXPECT_GT(with_normal, 20000u);
        EXPECT_LT(with_normal, count);
      }
    }
  }
}

TEST(TriangleMesh, VertexNormalsPointOutwardOnATetrahedron) {
  TriangleMesh m = test::tetrahedron();
  compute_vertex_normals(m);
  const Eigen::Vector3f centroid(0.25f, 0.25f, 0.25f);
  for (std::size_t i = 0; i < m.vertices.size(); ++i) {
    EXPECT_NEAR(m.normals[i].norm(), 1.0f, 1e-5f);
    EXPECT_GT(m.normals[i].dot(m.vertices[i] - centroid), 0.0f);
  }
  EXPECT_TRUE(face_normal(m, m.triangles[0]).isApprox(Eigen::Vector3f(0, 0, -1)));
}

// An n x n vertex grid on a wavy height field, two triangles per quad, vertices numbered in a
// scrambled order so rows of the incidence are not contiguous in the triangle list.
TriangleMesh wavy_grid(std::uint32_t n) {
  TriangleMesh m;
  std::vector<std::uint32_t> id(n * n);
  for (std::uint32_t i = 0; i < n * n; ++i) id[i] = (i * 7919u) % (n * n);  // n*n prime to 7919
  m.vertices.resize(n * n);
  for (std::uint32_t y = 0; y < n; ++y)
    for (std::uint32_t x = 0; x < n; ++x)
      m.vertices[id[y * n + x]] = {static_cast<float>(x), static_cast<float>(y),
                                   std::sin(0.3f * static_cast<float>(x * y))};
  for (std::uint32_t y = 0; y + 1 < n; ++y)
    for (std::uint32_t x = 0; x + 1 < n; ++x) {
      const std::uint32_t a = id[y * n + x], b = id[y * n + x + 1], c = id[(y + 1) * n + x],
                          d = id[(y + 1) * n + x + 1];
      m.triangles.push_back({a, b, d});
      m.triangles.push_back({a, d, c});
    }
  return m;
}

TEST(VertexTriangles, MatchesABruteForceIncidenceForAnyWorkerCount) {
  const TriangleMesh m = wavy_grid(150);
  std::vector<std::vector<std::uint32_t>> oracle(m.vertices.size());
  for (std::uint32_t t = 0; t < m.triangles.size(); ++t)
    for (std::uint32_t v : m.triangles[t]) oracle[v].push_back(t);
  const auto expect_oracle = [&](const VertexTriangles& around) {
    ASSERT_EQ(around.offsets.size(), m.vertices.size() + 1);
    for (std::uint32_t v = 0; v < m.vertices.size(); ++v)
      ASSERT_EQ(std::vector<std::uint32_t>(around.begin(v), around.end(v)), oracle[v]) << v;
  };
  for (int threads : {1, 2}) {
    ThreadLimit limit(threads);
    expect_oracle(vertex_triangles(m));
  }
  // An arena of eight slots, even on two cores: the 44 402 triangles split into five chunks
  // (8 192 triangles each at least).
  tbb::task_arena eight(8);
  eight.execute([&] { expect_oracle(vertex_triangles(m)); });
}

// The fans around v by definition: v's slots (one per corner equal to v, in triangle order)
// joined when their triangles share a corner other than v (below vertex_count), numbered in
// order of their lowest slot. Brute force (tests only).
std::vector<std::uint32_t> fans_oracle(const std::vector<Triangle>& tris, std::uint32_t v,
                                       std::size_t vertex_count) {
  std::vector<std::uint32_t> slots;
  for (std::uint32_t t = 0; t < tris.size(); ++t)
    for (std::uint32_t x : tris[t])
      if (x == v) slots.push_back(t);
  const auto shares = [&](std::uint32_t a, std::uint32_t b) {
    for (std::uint32_t x : tris[a])
      for (std::uint32_t y : tris[b])
        if (x == y && x != v && x < vertex_count) return true;
    return false;
  };
  std::vector<std::uint32_t> fan(slots.size(), UINT32_MAX);
  std::uint32_t fans = 0;
  for (std::size_t s = 0; s < slots.size(); ++s) {
    if (fan[s] != UINT32_MAX) continue;
    std::vector<std::size_t> stack{s};  // flood fill from the lowest unreached slot
    fan[s] = fans;
    while (!stack.empty()) {
      const std::size_t a = stack.back();
      stack.pop_back();
      for (std::size_t b = 0; b < slots.size(); ++b)
        if (fan[b] == UINT32_MAX && shares(slots[a], slots[b])) {
          fan[b] = fans;
          stack.push_back(b);
        }
    }
    ++fans;
  }
  return fan;
}

// Meshes whose vertices have every kind of fan: messy meshes (copies, repeated corners, bow
// ties, flipped triangles), a wavy grid with holes punched in it (one oriented fan, open or
// closed, at most vertices), and a vertex with 2 x 20 triangles: two closed cones touching at
// their apex (more triangles than the pairwise path takes), plus a corner past the vertices.
std::vector<std::pair<std::vector<Triangle>, std::size_t>> fan_test_meshes() {
  std::vector<std::pair<std::vector<Triangle>, std::size_t>> out;
  for (std::uint32_t seed : {1u, 2u, 3u}) {
    const TriangleMesh m = test::messy_mesh(14, seed);
    out.emplace_back(m.triangles, m.vertices.size());
  }
  TriangleMesh grid = wavy_grid(40);
  std::vector<Triangle> holed;
  for (std::size_t t = 0; t < grid.triangles.size(); ++t)
    if ((t * 2654435761u) % 7 != 0) holed.push_back(grid.triangles[t]);
  out.emplace_back(holed, grid.vertices.size());
  std::vector<Triangle> cones;
  const std::uint32_t rim = 20;
  for (std::uint32_t cone = 0; cone < 2; ++cone)
    for (std::uint32_t i = 0; i < rim; ++i)
      cones.push_back({0, 1 + cone * rim + i, 1 + cone * rim + (i + 1) % rim});
  cones.push_back({0, 5, 99});  // 99 is past the 41 vertices: not a spoke
  out.emplace_back(cones, 2 * rim + 1);
  return out;
}

TEST(VertexFans, MatchTheDefinitionOnEveryKindOfVertex) {
  for (const auto& mesh : fan_test_meshes()) {
    const std::vector<Triangle>& tris = mesh.first;  // (no structured binding: lambdas use it)
    const std::size_t n = mesh.second;
    const VertexTriangles around = vertex_triangles(tris, n);
    for (int threads : {1, 2}) {
      std::vector<std::uint32_t> fan;
      const std::vector<std::uint32_t> fans =
          test::with_threads(threads, [&] { return vertex_fans(tris, around, fan); });
      for (std::uint32_t v = 0; v < n; ++v) {
        const std::vector<std::uint32_t> expected = fans_oracle(tris, v, n);
        const std::vector<std::uint32_t> got(fan.begin() + around.offsets[v],
                                             fan.begin() + around.offsets[v + 1]);
        ASSERT_EQ(got, expected) << "vertex " << v << ", threads " << threads;
        const std::uint32_t count =
            expected.empty() ? 0 : *std::max_element(expected.begin(), expected.end()) + 1;
        ASSERT_EQ(fans[v], count) << "vertex " << v;
      }
    }
  }
  // The two cones' apex: two closed fans of 20 (and the lone triangle through vertex 5 joins the
  // first cone's fan there).
  const auto [cones, n] = fan_test_meshes().back();  // (a copy: the list is a temporary)
  std::vector<std::uint32_t> fan;
  EXPECT_EQ(vertex_fans(cones, vertex_triangles(cones, n), fan)[0], 2u);
}

TEST(VertexFans, RemovingTheSmallerFansLeavesOneFanEverywhereWithAnyThreadCount) {
  for (const auto& mesh : fan_test_meshes()) {
    const std::vector<Triangle>& tris = mesh.first;  // (no structured binding: lambdas use it)
    const std::size_t n = mesh.second;
    std::vector<Triangle> results[2];
    for (int threads : {1, 2}) {
      std::vector<Triangle> kept = tris;
      test::with_threads(threads, [&] {
        remove_smaller_fans(kept, n);
        return 0;
      });
      for (std::uint32_t v = 0; v < n; ++v) {
        const std::vector<std::uint32_t> fan = fans_oracle(kept, v, n);
        ASSERT_TRUE(std::all_of(fan.begin(), fan.end(), [](std::uint32_t f) { return f == 0; }))
            << "vertex " << v;
      }
      // Only removals, the rest in order: `kept` is a subsequence of `tris`.
      std::size_t at = 0;
      for (const Triangle& t : tris)
        if (at < kept.size() && kept[at] == t) ++at;
      EXPECT_EQ(at, kept.size());
      EXPECT_LT(kept.size(), tris.size());
      results[threads - 1] = kept;
    }
    EXPECT_EQ(results[0], results[1]);
    EXPECT_FALSE(results[0].empty());
  }
}

TEST(TriangleMesh, RenumberUsedVerticesKeepsTheirOrder) {
  std::vector<Triangle> tris{{7, 2, 9}, {2, 9, 4}, {9, 7, 4}};
  const std::vector<Triangle> before = tris;
  const std::vector<std::uint32_t> original = renumber_used_vertices(tris, 12);
  EXPECT_EQ(original, (std::vector<std::uint32_t>{2, 4, 7, 9}));
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(original[tris[t][k]], before[t][k]);
}

TEST(VertexTriangles, CornersPastTheVerticesAreLeftOut) {
  // Triangle 1 names vertex 7 of 4: its other corners are listed, that one nowhere.
  const std::vector<Triangle> tris{{0, 1, 2}, {1, 7, 3}, {2, 1, 3}};
  const VertexTriangles around = vertex_triangles(tris, 4);
  ASSERT_EQ(around.offsets.size(), 5u);
  EXPECT_EQ(around.triangles.size(), 8u);
  EXPECT_EQ(std::vector<std::uint32_t>(around.begin(1), around.end(1)),
            (std::vector<std::uint32_t>{0, 1, 2}));
  EXPECT_EQ(std::vector<std::uint32_t>(around.begin(3), around.end(3)),
            (std::vector<std::uint32_t>{1, 2}));
}

TEST(TriangleMesh, BorderEdgesOfAGridAreItsOutlineDirectedAsTheirTriangles) {
  const std::uint32_t n = 150;
  const TriangleMesh m = wavy_grid(n);
  // Oracle: undirected edges used once, from a map.
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
  for (const Triangle& t : m.triangles)
    for (int i = 0; i < 3; ++i) ++uses[std::minmax(t[i], t[(i + 1) % 3])];
  std::size_t expected = 0;
  for (const auto& [edge, count] : uses) expected += count == 1 ? 1 : 0;
  ASSERT_EQ(expected, 4u * (n - 1));
  for (int threads : {1, 2}) {
    ThreadLimit limit(threads);
    const std::vector<BorderEdge> border = border_edges(m);
    ASSERT_EQ(border.size(), expected);
    for (const BorderEdge& e : border) {
      EXPECT_EQ(uses[std::minmax(e.a, e.b)], 1);
      const Triangle& t = m.triangles[e.triangle];
      const bool directed = (t[0] == e.a && t[1] == e.b) || (t[1] == e.a && t[2] == e.b) ||
                            (t[2] == e.a && t[0] == e.b);
      EXPECT_TRUE(directed);
    }
    EXPECT_TRUE(std::is_sorted(border.begin(), border.end(), [](const auto& x, const auto& y) {
      return x.triangle < y.triangle;
    }));
  }
}

// The definition, brute force: edge i of triangle t (a = t[i] -> b = t[i + 1]) is a border edge
// when no other triangle has both a and b as corners. O(T^2).
std::vector<BorderEdge> border_edges_oracle(const TriangleMesh& m) {
  const auto holds = [](const Triangle& t, std::uint32_t x) {
    return t[0] == x || t[1] == x || t[2] == x;
  };
  std::vector<BorderEdge> border;
  for (std::uint32_t t = 0; t < m.triangles.size(); ++t)
    for (std::size_t i = 0; i < 3; ++i) {
      const std::uint32_t a = m.triangles[t][i], b = m.triangles[t][(i + 1) % 3];
      bool alone = true;
      for (std::uint32_t s = 0; s < m.triangles.size() && alone; ++s)
        alone = s == t || !(holds(m.triangles[s], a) && holds(m.triangles[s], b));
      if (alone) border.push_back({a, b, t});
    }
  return border;
}

TEST(TriangleMesh, BorderEdgesMatchTheDefinitionOnMessyMeshes) {
  for (std::uint32_t seed : {1u, 2u, 3u}) {
    const TriangleMesh m = test::messy_mesh(14, seed);  // copies, repeated corners, bow ties
    const std::vector<BorderEdge> expected = border_edges_oracle(m);
    for (int threads : {1, 2}) {
      const std::vector<BorderEdge> border =
          test::with_threads(threads, [&] { return border_edges(m); });
      ASSERT_EQ(border.size(), expected.size()) << "seed " << seed << ", threads " << threads;
      for (std::size_t k = 0; k < border.size(); ++k) {
        EXPECT_EQ(border[k].a, expected[k].a);
        EXPECT_EQ(border[k].b, expected[k].b);
        EXPECT_EQ(border[k].triangle, expected[k].triangle);
      }
    }
  }
}

TEST(TriangleMesh, HasAreaRefusesPointsLinesAndSlivers) {
  const Eigen::Vector3f a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_TRUE(has_area(a, b, c));
  EXPECT_TRUE(has_area(a, b, Eigen::Vector3f(0.5f, 1e-4f, 0)));   // thin, but 1e-4 of its length
  EXPECT_FALSE(has_area(a, a, c));                                // two corners on one point
  EXPECT_FALSE(has_area(a, b, Eigen::Vector3f(2, 0, 0)));         // collinear
  EXPECT_FALSE(has_area(a, b, Eigen::Vector3f(0.5f, 1e-8f, 0)));  // flatter than a millionth
}

TEST(TriangleMesh, VertexNormalsAreTheSerialSumsWithOneAndTwoThreads) {
  TriangleMesh m = wavy_grid(150);
  std::vector<Eigen::Vector3f> serial(m.vertices.size(), Eigen::Vector3f::Zero());
  for (const Triangle& t : m.triangles) {
    const Eigen::Vector3f n =
        (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]);
    for (std::uint32_t v : t) serial[v] += n;
  }
  for (auto& n : serial) n.normalize();
  for (int threads : {1, 2}) {
    ThreadLimit limit(threads);
    compute_vertex_normals(m);
    EXPECT_EQ(m.normals, serial);  // bit-identical: each vertex sums in triangle order
  }
}

}  // namespace
}  // namespace meshflow
