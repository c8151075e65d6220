#include "nodes/optimize/features.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "fixtures/mesh_fixtures.h"
#include "nodes/decimate/qem_decimation.h"
#include "nodes/optimize/feature_snap.h"
#include "runtime/disjoint_sets.h"
#include "runtime/threads.h"
#include "runtime/vertex_triangles.h"

namespace meshflow {
namespace {

using test::tessellated_cube;

bool is_cube_corner(const Eigen::Vector3f& p) {
  for (int k = 0; k < 3; ++k)
    if (p[k] != 0.0f && p[k] != 1.0f) return false;
  return true;
}

// Whether p lies on one of the cube's 12 edges (two coordinates at 0 or 1).
bool on_cube_edge(const Eigen::Vector3f& p) {
  int extreme = 0;
  for (int k = 0; k < 3; ++k) extreme += (p[k] == 0.0f || p[k] == 1.0f) ? 1 : 0;
  return extreme >= 2;
}

TEST(Features, ACubesTwelveEdgesAndEightCorners) {
  const int n = 6;
  const TriangleMesh cube = tessellated_cube(n);
  const MeshFeatures f = detect_features(cube);
  EXPECT_EQ(f.edges.size(), 12u * n);
  EXPECT_EQ(f.count(MeshFeatures::VertexKind::kCorner), 8u);
  EXPECT_EQ(f.count(MeshFeatures::VertexKind::kLine), 12u * (n - 1));
  for (const auto& e : f.edges) {
    EXPECT_TRUE(on_cube_edge(cube.vertices[e[0]]));
    EXPECT_TRUE(on_cube_edge(cube.vertices[e[1]]));
    EXPECT_TRUE(f.has_edge(e[1], e[0]));
  }
  for (std::uint32_t v = 0; v < cube.vertices.size(); ++v)
    EXPECT_EQ(f.vertex_kind[v] == MeshFeatures::VertexKind::kCorner,
              is_cube_corner(cube.vertices[v]));
  // 90-degree edges are not sharp above 90 degrees; 180 turns detection off.
  EXPECT_TRUE(detect_features(cube, 91.0f).edges.empty());
  EXPECT_TRUE(detect_features(cube, 180.0f).edges.empty());
}

// The cube with its face-interior vertices pushed along the face normal by up to `amplitude`
// grid steps (a fixed pseudo-random pattern): bumps that the dihedral test alone fires on, the
// cube's edges and corners exactly where they were.
TriangleMesh bumpy_cube(int n, float amplitude) {
  TriangleMesh m = tessellated_cube(n);
  for (std::size_t v = 0; v < m.vertices.size(); ++v) {
    Eigen::Vector3f& p = m.vertices[v];
    int axis = -1, extremes = 0;
    for (int k = 0; k < 3; ++k)
      if (p[k] == 0.0f || p[k] == 1.0f) axis = k, ++extremes;
    if (extremes != 1) continue;  // on an edge or a corner
    const double hash = std::sin(12.9898 * static_cast<double>(v) + 78.233) * 43758.5453;
    const float unit = static_cast<float>(2.0 * (hash - std::floor(hash)) - 1.0);  // [-1, 1)
    p[axis] += (p[axis] == 0.0f ? -1.0f : 1.0f) * amplitude * unit / static_cast<float>(n);
  }
  return m;
}

TEST(Features, BumpsAreNoiseTheCubesLinesStay) {
  const int n = 16;
  const TriangleMesh tessellated = tessellated_cube(n);
  const TriangleMesh cube = bumpy_cube(n, 0.35f);
  // Every candidate kept (min_line_length < 0): the bumps fire the 40-degree test.
  const MeshFeatures all = detect_features(cube, kDefaultFeatureAngleDeg, -1.0f);
  std::size_t off_edges = 0;
  for (const auto& e : all.edges)
    off_edges +=
        on_cube_edge(tessellated.vertices[e[0]]) && on_cube_edge(tessellated.vertices[e[1]]) ? 0
                                                                                             : 1;
  EXPECT_GT(off_edges, 100u);
  // Short, branching, zigzagging lines dropped: nothing off the cube's edges is kept, most of
  // the 12 edges are (where bumps beside an edge turn its side's faces by more than twice the
  // feature angle the line breaks there, and a piece may fall below the minimum length).
  const MeshFeatures f = detect_features(cube);
  std::printf(
      "[ features ] bumpy cube: %zu candidates (%zu off the edges), %zu kept, %zu corners\n",
      all.edges.size(), off_edges, f.edges.size(), f.count(MeshFeatures::VertexKind::kCorner));
  EXPECT_GE(f.edges.size(), 12u * n * 3 / 4);
  for (const auto& e : f.edges)
    EXPECT_TRUE(on_cube_edge(tessellated.vertices[e[0]]) &&
                on_cube_edge(tessellated.vertices[e[1]]));
  EXPECT_LE(f.count(MeshFeatures::VertexKind::kCorner), 16u);
}

TEST(Features, SnapPutsAStrayEdgeVertexBackOnTheEdge) {
  // A vertex in the middle of an edge pushed off it by 0.3 grid steps goes back onto the edge
  // (the intersection of its two sides' planes) at the same place along it.
  const int n = 10;
  const TriangleMesh exact = tessellated_cube(n);
  TriangleMesh cube = exact;
  const auto stray = static_cast<std::uint32_t>(
      std::find(exact.vertices.begin(), exact.vertices.end(), Eigen::Vector3f(0.5f, 0.0f, 0.0f)) -
      exact.vertices.begin());
  ASSERT_LT(stray, exact.vertices.size());
  cube.vertices[stray] += 0.3f / n * Eigen::Vector3f(0.0f, -1.0f, -1.0f).normalized();
  const MeshFeatures f = detect_features(cube);
  ASSERT_EQ(f.edges.size(), 12u * n);  // the stray vertex bends the faces, not the graph
  const FeatureSnapReport r = snap_feature_vertices(cube, f, 0.5f / n, 0.01f / n);
  EXPECT_EQ(r.moved, 1u);
  EXPECT_LT((cube.vertices[stray] - exact.vertices[stray]).norm(), 1e-5f);
  EXPECT_EQ(cube.vertices, [&] {
    TriangleMesh m = exact;  // nothing else moved
    m.vertices[stray] = cube.vertices[stray];
    return m.vertices;
  }());
  // Not that far: it stays.
  TriangleMesh again = exact;
  again.vertices[stray] += 0.3f / n * Eigen::Vector3f(0.0f, -1.0f, -1.0f).normalized();
  EXPECT_EQ(snap_feature_vertices(again, detect_features(again), 0.01f / n, 0.01f / n).moved, 0u);
}

// Brute force: every undirected edge with exactly two faces whose unit normals meet at more
// than `angle_deg`, from a map of every face's sides.
std::vector<std::array<std::uint32_t, 2>> brute_force_sharp_edges(const TriangleMesh& m,
                                                                  float angle_deg) {
  std::map<std::array<std::uint32_t, 2>, std::vector<std::uint32_t>> sides;
  for (std::uint32_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = m.triangles[t][k], b = m.triangles[t][(k + 1) % 3];
      sides[{std::min(a, b), std::max(a, b)}].push_back(t);
    }
  const double cos_limit = std::cos(angle_deg * M_PI / 180.0);
  std::vector<std::array<std::uint32_t, 2>> out;
  for (const auto& [edge, faces] : sides) {
    if (faces.size() != 2 || faces[0] == faces[1]) continue;
    const Eigen::Vector3f n0 = face_normal(m, m.triangles[faces[0]]);
    const Eigen::Vector3f n1 = face_normal(m, m.triangles[faces[1]]);
    if (n0.squaredNorm() > 0.0f && n1.squaredNorm() > 0.0f && n0.dot(n1) < cos_limit)
      out.push_back(edge);
  }
  return out;
}

TEST(Features, SharpEdgesAreTheBruteForceOnesForAnyThreadCount) {
  // The bumpy cube (many candidates) with a border (two faces removed) and a non-manifold edge
  // (a fin on one of its edges: three faces there, never sharp).
  TriangleMesh m = bumpy_cube(12, 0.35f);
  m.triangles.erase(m.triangles.begin() + 40, m.triangles.begin() + 42);
  const Triangle fin_base = m.triangles[100];
  m.vertices.push_back(m.vertices[fin_base[0]] + Eigen::Vector3f(0.3f, 0.2f, 0.1f));
  m.triangles.push_back(
      {fin_base[1], fin_base[0], static_cast<std::uint32_t>(m.vertices.size() - 1)});
  const auto expected = brute_force_sharp_edges(m, kDefaultFeatureAngleDeg);
  ASSERT_GT(expected.size(), 100u);
  MeshFeatures one, two;
  {
    ThreadLimit limit(1);
    one = detect_features(m, kDefaultFeatureAngleDeg, -1.0f);
  }
  {
    ThreadLimit limit(2);
    two = detect_features(m, kDefaultFeatureAngleDeg, -1.0f);
  }
  EXPECT_EQ(one.edges, expected);
  EXPECT_EQ(two.edges, expected);
  EXPECT_EQ(one.vertex_kind, two.vertex_kind);
  EXPECT_FALSE(one.has_edge(fin_base[0], fin_base[1]));
}

TEST(Features, DecimationKeepsCornersAndCollapsesEdgesOnlyAlongThemselves) {
  const TriangleMesh cube = tessellated_cube(12);
  const MeshFeatures f = detect_features(cube);
  QemConfig config;
  config.divide_by_depth2 = false;
  config.target_ratio = 0.02f;  // far below what a cube needs: only the constraints stop it
  QemReport report;
  const TriangleMesh out = qem_decimate(cube, f.edges, config, &report);
  EXPECT_LT(out.triangles.size(), cube.triangles.size() / 10);
  EXPECT_GT(report.rejected_feature, 0u);
  std::size_t corners = 0;
  for (const Eigen::Vector3f& p : out.vertices) {
    corners += is_cube_corner(p) ? 1 : 0;
    // Output vertices are input vertices: every one still on the cube's surface.
    EXPECT_TRUE(p.minCoeff() == 0.0f || p.maxCoeff() == 1.0f);
  }
  EXPECT_EQ(corners, 8u);
  // Every sharp edge of the output joins two points of one cube edge (a chord of a feature
  // line), and the 12 lines are all still there: 12 sharp edges at least.
  // (Every candidate: one mesh edge per cube edge is a line far shorter than the default
  // minimum, 5 of the coarse mesh's median edges.)
  const MeshFeatures kept = detect_features(out, kDefaultFeatureAngleDeg, -1.0f);
  EXPECT_GE(kept.edges.size(), 12u);
  for (const auto& e : kept.edges) {
    const Eigen::Vector3f a = out.vertices[e[0]], b = out.vertices[e[1]];
    EXPECT_TRUE(on_cube_edge(a) && on_cube_edge(b));
    int shared = 0;
    for (int k = 0; k < 3; ++k) shared += (a[k] == b[k] && (a[k] == 0.0f || a[k] == 1.0f)) ? 1 : 0;
    EXPECT_EQ(shared, 2) << "a sharp edge cuts across a face";
  }
  // Without features the same target cuts the corners and faces across the edges.
  const TriangleMesh plain = qem_decimate(cube, config);
  std::size_t plain_corners = 0;
  for (const Eigen::Vector3f& p : plain.vertices) plain_corners += is_cube_corner(p) ? 1 : 0;
  std::printf(
      "[ features ] cube %zu -> %zu triangles with features (8 corners), %zu without "
      "(%zu corners)\n",
      cube.triangles.size(), out.triangles.size(), plain.triangles.size(), plain_corners);
}

TEST(Features, NoFeaturesGivesThePlainDecimation) {
  const TriangleMesh cube = tessellated_cube(8);
  QemConfig config;
  config.divide_by_depth2 = false;
  const TriangleMesh a = qem_decimate(cube, config);
  const TriangleMesh b = qem_decimate(cube, {}, config);
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.triangles, b.triangles);
}

// The same oracle on the faces an edge map must tell apart: a third face on an edge, a face given
// twice and a face with a repeated corner (none of their edges is sharp).
TEST(Features, SharpEdgesMatchABruteForceEdgeMap) {
  TriangleMesh mesh = bumpy_cube(9, 0.35f);
  const auto n = static_cast<std::uint32_t>(mesh.vertices.size());
  const Triangle first = mesh.triangles[0], last = mesh.triangles.back();
  mesh.vertices.push_back({0.5f, 0.5f, 2.0f});
  mesh.triangles.push_back({first[0], first[1], n});  // a third face on an edge
  mesh.triangles.push_back(last);                     // a face given twice
  mesh.triangles.push_back({first[2], first[2], n});  // a repeated corner
  const auto expected = brute_force_sharp_edges(mesh, 40.0f);
  ASSERT_GT(expected.size(), 12u * 9u);  // the cube's edges and the bumps'
  for (int threads : {1, 2}) {
    ThreadLimit limit(threads);
    EXPECT_EQ(detect_features(mesh, 40.0f, -1.0f).edges, expected) << threads << " threads";
  }
}

// The whole mesh's feature graph on the sets of brute-force candidates (joined at shared
// vertices) that hold a seed, kFree elsewhere: what detect_features_reaching() must give.
MeshFeatures whole_graph_reaching(const TriangleMesh& m, const std::vector<std::uint32_t>& seeds,
                                  float min_line_length) {
  const auto candidates = brute_force_sharp_edges(m, kDefaultFeatureAngleDeg);
  DisjointSets sets(m.vertices.size());
  std::vector<std::uint8_t> on_candidate(m.vertices.size(), 0);
  for (const auto& e : candidates) {
    sets.unite(e[0], e[1]);
    on_candidate[e[0]] = on_candidate[e[1]] = 1;
  }
  const std::vector<std::uint32_t> set_of = sets.labels();
  std::vector<std::uint8_t> reached(m.vertices.size(), 0);
  for (std::uint32_t v : seeds)
    if (on_candidate[v]) reached[set_of[v]] = 1;
  const MeshFeatures whole = detect_features(m, kDefaultFeatureAngleDeg, min_line_length);
  MeshFeatures expected;
  for (const auto& e : whole.edges)
    if (reached[set_of[e[0]]]) expected.edges.push_back(e);
  expected.vertex_kind.assign(m.vertices.size(), MeshFeatures::VertexKind::kFree);
  for (std::uint32_t v = 0; v < m.vertices.size(); ++v)
    if (on_candidate[v] && reached[set_of[v]]) expected.vertex_kind[v] = whole.vertex_kind[v];
  return expected;
}

// The lines found from a few seeds are the whole mesh's lines there, for the noisy bumps'
// candidate sets (most dropped as short) as for the cube's edges (kept), for any thread count;
// seeded everywhere, the whole graph.
TEST(Features, LinesReachingSeedsAreTheWholeGraphsThere) {
  TriangleMesh m = bumpy_cube(12, 0.35f);
  m.triangles.erase(m.triangles.begin() + 40, m.triangles.begin() + 42);  // a border
  const VertexTriangles around = vertex_triangles(m);
  std::vector<std::uint32_t> everywhere(m.vertices.size());
  for (std::uint32_t v = 0; v < everywhere.size(); ++v) everywhere[v] = v;
  std::vector<std::uint32_t> corner;  // a cube corner: the graph of the cube's edges
  for (std::uint32_t v = 0; v < m.vertices.size() && corner.empty(); ++v)
    if (is_cube_corner(m.vertices[v])) corner.push_back(v);
  std::vector<std::uint32_t> scattered;  // every 37th vertex: bumps, edges and flat places
  for (std::uint32_t v = 0; v < m.vertices.size(); v += 37) scattered.push_back(v);
  std::vector<std::uint32_t> border(m.triangles[40].begin(), m.triangles[40].end());
  std::size_t nonempty = 0;
  for (float min_line_length : {0.0f, -1.0f, 0.3f})
    for (const auto* seeds : {&everywhere, &corner, &scattered, &border}) {
      const MeshFeatures expected = whole_graph_reaching(m, *seeds, min_line_length);
      nonempty += expected.edges.empty() ? 0 : 1;
      for (int threads : {1, 2}) {
        ThreadLimit limit(threads);
        const MeshFeatures f =
            detect_features_reaching(m, around, *seeds, kDefaultFeatureAngleDeg, min_line_length);
        EXPECT_EQ(f.edges, expected.edges) << min_line_length << ", " << seeds->size();
        EXPECT_EQ(f.vertex_kind, expected.vertex_kind) << min_line_length << ", " << seeds->size();
      }
    }
  EXPECT_GE(nonempty, 9u);
  // With the maker's marks (every 5th vertex and the cube's edges; short marked lines stay): the
  // seeded whole graph, and the seeded graph on a given incidence is the same.
  std::vector<std::uint8_t> marks(m.vertices.size(), 0);
  for (std::uint32_t v = 0; v < marks.size(); ++v)
    marks[v] = v % 5 == 0 || on_cube_edge(m.vertices[v]) ? 1 : 0;
  const MeshFeatures seeded = detect_features(m, marks);
  EXPECT_EQ(
      detect_features_reaching(m, around, everywhere, kDefaultFeatureAngleDeg, 0.0f, &marks).edges,
      seeded.edges);
  EXPECT_NE(seeded.edges, detect_features(m).edges);  // the marks kept short lines
  EXPECT_EQ(detect_features(m, around, &marks).edges, seeded.edges);
  EXPECT_EQ(detect_features(m, around, &marks).vertex_kind, seeded.vertex_kind);
  EXPECT_EQ(detect_features(m, around, nullptr).edges, detect_features(m).edges);
  const MeshFeatures whole = detect_features(m);
  EXPECT_EQ(detect_features_reaching(m, around, everywhere).edges, whole.edges);
  EXPECT_TRUE(detect_features_reaching(m, around, {}).edges.empty());
  EXPECT_TRUE(detect_features_reaching(m, around, everywhere, 180.0f).edges.empty());
}

}  // namespace
}  // namespace meshflow
