#include "nodes/optimize/cleanup/hole_filling.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

#include "fixtures/mesh_fixtures.h"
#include "nodes/optimize/features.h"
#include "runtime/half_edge_mesh.h"
#include "test_support.h"

namespace meshflow {
namespace {

constexpr std::uint32_t kGrid = 20;

// The 20 x 20 grid with three holes: the star of vertex (5, 14) (6 edges), the 2 x 2 cells at
// (12..14, 12..14) (8 edges) and the 5 x 5 cells at (3..8, 3..8) (20 edges).
TriangleMesh holed_grid() {
  const std::uint32_t star = 14 * kGrid + 5;
  const TriangleMesh full = test::grid_mesh(kGrid);
  TriangleMesh m = test::without_faces(full, [](const Eigen::Vector3f& c) {
    auto in_block = [&](float lo, float hi) {
      return c.x() > lo && c.x() < hi && c.y() > lo && c.y() < hi;
    };
    return in_block(12, 14) || in_block(3, 8);
  });
  m.triangles.erase(
      std::remove_if(m.triangles.begin(), m.triangles.end(),
                     [&](const Triangle& t) { return std::count(t.begin(), t.end(), star) > 0; }),
      m.triangles.end());
  return m;
}

double area(const TriangleMesh& m, const Triangle& t) {
  return 0.5 * static_cast<double>((m.vertices[t[1]] - m.vertices[t[0]])
                                       .cross(m.vertices[t[2]] - m.vertices[t[0]])
                                       .norm());
}

TEST(HoleFilling, ClosesSmallHolesOfAFlatScanAndKeepsItsOutlineAndLargeHoles) {
  const TriangleMesh in = holed_grid();
  HoleFillingConfig config;
  config.max_edges = 10;
  HoleFillingReport report;
  const TriangleMesh out = fill_holes(in, config, &report);
  EXPECT_EQ(report.loops, 4u);
  EXPECT_EQ(report.outer_borders, 1u);
  EXPECT_EQ(report.too_large, 1u);
  EXPECT_EQ(report.filled, 2u);
  EXPECT_EQ(report.not_fillable, 0u);
  EXPECT_EQ(report.added_triangles, 4u + 6u);  // a hexagon and an octagon
  EXPECT_EQ(out.vertices, in.vertices);
  ASSERT_EQ(out.triangles.size(), in.triangles.size() + report.added_triangles);
  EXPECT_TRUE(std::equal(in.triangles.begin(), in.triangles.end(), out.triangles.begin()));

  ASSERT_EQ(test::half_edge_problem(out), "");
  const HalfEdgeMesh h(out);
  const auto loops = h.border_loops();
  ASSERT_EQ(loops.size(), 2u);  // the outline and the 20-edge hole
  std::set<std::size_t> sizes{loops[0].size(), loops[1].size()};
  EXPECT_EQ(sizes, (std::set<std::size_t>{20u, 4u * (kGrid - 1)}));
  // New triangles face +z like the grid, have area, and tile the holes exactly.
  double added = 0.0;
  for (std::size_t t = in.triangles.size(); t < out.triangles.size(); ++t) {
    EXPECT_GT(face_normal(out, out.triangles[t]).z(), 0.999f);
    EXPECT_GT(area(out, out.triangles[t]), 0.1);
    added += area(out, out.triangles[t]);
  }
  EXPECT_NEAR(added, 3.0 + 4.0, 1e-4);  // the star covered 6 half cells, the block 4 cells
  const EdgeStatistics edges = edge_statistics(out);
  EXPECT_EQ(edges.non_manifold_edges, 0u);
  EXPECT_EQ(edges.inconsistent_edges, 0u);
}

TEST(HoleFilling, TheOnlyLoopOfAComponentIsItsOutlineUnlessToldOtherwise) {
  // An octahedron without its last face: one loop of three edges.
  TriangleMesh m;
  m.vertices = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                 {2, 0, 5}, {1, 2, 5}, {3, 1, 5}};  // {0, 3, 5} missing
  HoleFillingReport report;
  EXPECT_EQ(fill_holes(m, {}, &report).triangles.size(), m.triangles.size());
  EXPECT_EQ(report.outer_borders, 1u);
  EXPECT_EQ(report.filled, 0u);

  HoleFillingConfig closed;
  closed.keep_outer_border = false;
  const TriangleMesh out = fill_holes(m, closed, &report);
  EXPECT_EQ(report.filled, 1u);
  ASSERT_EQ(out.triangles.size(), 8u);
  EXPECT_EQ(edge_statistics(out).boundary_edges, 0u);  // closed again
  EXPECT_EQ(HalfEdgeMesh(out).check(), "");
  const Eigen::Vector3f n = face_normal(out, out.triangles.back());
  EXPECT_GT(n.dot(Eigen::Vector3f(1, -1, -1).normalized()), 0.999f);  // faces outwards
}

TEST(HoleFilling, StraightBordersGetNoTrianglesWithoutArea) {
  // A 2 x 3 cell hole: its border has three collinear vertices on each long side.
  const TriangleMesh m = test::without_faces(test::grid_mesh(8), [](const Eigen::Vector3f& c) {
    return c.x() > 2 && c.x() < 4 && c.y() > 2 && c.y() < 5;
  });
  HoleFillingReport report;
  const TriangleMesh out = fill_holes(m, {}, &report);
  EXPECT_EQ(report.filled, 1u);
  EXPECT_EQ(report.added_triangles, 8u);
  double added = 0.0;
  for (std::size_t t = m.triangles.size(); t < out.triangles.size(); ++t) {
    EXPECT_GT(area(out, out.triangles[t]), 0.1);
    added += area(out, out.triangles[t]);
  }
  EXPECT_NEAR(added, 6.0, 1e-4);
  EXPECT_EQ(HalfEdgeMesh(out).check(), "");
}

// Whether the triangle lies in one face of the unit cube (its corners share a coordinate at 0
// or 1, within `tolerance`).
bool in_one_cube_face(const TriangleMesh& m, const Triangle& t, float tolerance) {
  for (int k = 0; k < 3; ++k)
    for (float side : {0.0f, 1.0f}) {
      bool all = true;
      for (std::uint32_t v : t) all &= std::abs(m.vertices[v][k] - side) <= tolerance;
      if (all) return true;
    }
  return false;
}

// The cube (20 x 20 squares a face) without its faces within `radius` of `centre`.
TriangleMesh cube_with_hole(const Eigen::Vector3f& centre, float radius) {
  return test::without_faces(test::tessellated_cube(20), [&](const Eigen::Vector3f& c) {
    return (c - centre).norm() < radius;
  });
}

// Fills the cube's one hole with (feature_angle 40) or without (180) features; every new
// triangle must lie in a face of the cube.
std::size_t triangles_off_the_cube(const TriangleMesh& holed, float feature_angle,
                                   HoleFillingReport& report, TriangleMesh& out) {
  HoleFillingConfig config;
  config.feature_angle_deg = feature_angle;
  config.feature_min_length = 0.1f;  // the lines cut by the hole stay lines
  out = fill_holes(holed, config, &report);
  EXPECT_EQ(report.filled, 1u);
  EXPECT_EQ(test::half_edge_problem(out), "");
  EXPECT_EQ(edge_statistics(out).boundary_edges, 0u);
  std::size_t off = 0;
  for (std::size_t t = holed.triangles.size(); t < out.triangles.size(); ++t)
    off += in_one_cube_face(out, out.triangles[t], 1e-5f) ? 0 : 1;
  return off;
}

TEST(HoleFilling, AHoleAcrossAnEdgeIsFilledAlongTheEdge) {
  // A hole on the cube's edge y = z = 0: the smallest fill cuts the edge off (a chamfer has
  // less area); along the feature line it is the two faces again, and the edge is whole.
  const TriangleMesh holed = cube_with_hole({0.5f, 0.0f, 0.0f}, 0.15f);
  HoleFillingReport report;
  TriangleMesh out;
  const std::size_t plain_off = triangles_off_the_cube(holed, 180.0f, report, out);
  EXPECT_GT(plain_off, 0u);
  EXPECT_EQ(report.along_features, 0u);
  EXPECT_EQ(triangles_off_the_cube(holed, kDefaultFeatureAngleDeg, report, out), 0u);
  EXPECT_EQ(report.along_features, 1u);
  EXPECT_EQ(report.centre_vertices, 0u);
  EXPECT_EQ(out.vertices, holed.vertices);
  // The edge is one feature line again: its sharp edges cover it end to end.
  const MeshFeatures f = detect_features(out);
  float covered = 0.0f;
  for (const auto& e : f.edges) {
    const Eigen::Vector3f a = out.vertices[e[0]], b = out.vertices[e[1]];
    if (a.y() == 0.0f && a.z() == 0.0f && b.y() == 0.0f && b.z() == 0.0f) covered += (b - a).norm();
  }
  EXPECT_NEAR(covered, 1.0f, 1e-5f);
  std::printf("[ holes ] edge hole: %zu of %zu fill triangles off the cube without features\n",
              plain_off, out.triangles.size() - holed.triangles.size());
}

TEST(HoleFilling, AHoleOverACornerGetsTheCornerBack) {
  // Three feature lines end on the hole around the corner (1, 1, 1): the fill adds a vertex
  // where they meet and joins each arc of the border to it.
  const TriangleMesh holed = cube_with_hole({1.0f, 1.0f, 1.0f}, 0.15f);
  HoleFillingReport report;
  TriangleMesh out;
  const std::size_t plain_off = triangles_off_the_cube(holed, 180.0f, report, out);
  EXPECT_GT(plain_off, 0u);
  EXPECT_EQ(triangles_off_the_cube(holed, kDefaultFeatureAngleDeg, report, out), 0u);
  EXPECT_EQ(report.along_features, 1u);
  ASSERT_EQ(out.vertices.size(), holed.vertices.size() + 1);
  EXPECT_LT((out.vertices.back() - Eigen::Vector3f(1, 1, 1)).norm(), 1e-5f);
  const MeshFeatures f = detect_features(out);
  EXPECT_EQ(f.vertex_kind.back(), MeshFeatures::VertexKind::kCorner);
  EXPECT_EQ(f.count(MeshFeatures::VertexKind::kCorner), 8u);
}

// The features the optimize steps carry: the whole mesh's graph gives the fills the detection
// from the holes gives (edge and corner holes); the mesh maker's marks keep lines the length
// test would drop (every line shorter than 10 m here): the fill continues them, as with lines
// long enough, where without the marks it cuts the edge off.
TEST(HoleFilling, CarriedGraphAndMarksGiveTheFillsOfTheirLines) {
  for (const Eigen::Vector3f& at : {Eigen::Vector3f(0.5f, 0.0f, 0.0f), Eigen::Vector3f(1, 1, 1)}) {
    const TriangleMesh holed = cube_with_hole(at, 0.15f);
    HoleFillingConfig config;
    config.feature_min_length = 0.1f;
    const MeshFeatures graph =
        detect_features(holed, config.feature_angle_deg, config.feature_min_length);
    HoleFeatures known;
    known.graph = &graph;
    HoleFillingReport detected, carried;
    const TriangleMesh a = fill_holes(holed, config, &detected);
    const TriangleMesh b = fill_holes(holed, config, &carried, nullptr, known);
    EXPECT_EQ(a.triangles, b.triangles);
    EXPECT_EQ(a.vertices, b.vertices);
    EXPECT_EQ(carried.along_features, 1u);

    config.feature_min_length = 10.0f;  // every line is noise now
    std::vector<std::uint8_t> marks(holed.vertices.size(), 0);
    for (std::size_t v = 0; v < marks.size(); ++v) {
      int extreme = 0;  // on a cube edge: two coordinates at 0 or 1
      for (int k = 0; k < 3; ++k)
        extreme += holed.vertices[v][k] == 0.0f || holed.vertices[v][k] == 1.0f ? 1 : 0;
      marks[v] = extreme >= 2 ? 1 : 0;
    }
    HoleFillingReport unmarked, marked;
    const TriangleMesh plain = fill_holes(holed, config, &unmarked);
    HoleFeatures from_marks;
    from_marks.marks = &marks;
    const TriangleMesh seeded = fill_holes(holed, config, &marked, nullptr, from_marks);
    EXPECT_EQ(unmarked.along_features, 0u);
    EXPECT_EQ(marked.along_features, 1u);
    EXPECT_EQ(seeded.triangles, b.triangles);  // the fill of the long lines
    EXPECT_NE(plain.triangles, b.triangles);
  }
}

TEST(HoleFilling, SameTrianglesWithOneAndTwoThreads) {
  const TriangleMesh in = holed_grid();
  const auto one = test::with_threads(1, [&] { return fill_holes(in).triangles; });
  const auto two = test::with_threads(2, [&] { return fill_holes(in).triangles; });
  EXPECT_GT(one.size(), in.triangles.size());  // the holes got triangles
  EXPECT_EQ(one, two);
}

}  // namespace
}  // namespace meshflow
