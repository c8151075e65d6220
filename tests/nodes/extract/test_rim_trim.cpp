#include "nodes/extract/rim_trim.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "test_support.h"

namespace meshflow {
namespace {

// Points every 0.1 on the unit square [0, 1]^2 at z = 0.
std::vector<Eigen::Vector3f> square_points() {
  std::vector<Eigen::Vector3f> p;
  for (int i = 0; i <= 10; ++i)
    for (int j = 0; j <= 10; ++j) p.emplace_back(0.1f * i, 0.1f * j, 0.0f);
  return p;
}

// A mesh over [0, 3] x [0, 1] with unit... 0.1 spacing: it runs 2 past the data along x.
TriangleMesh long_grid() {
  TriangleMesh m = test::grid_mesh(31);  // 31 x 31 vertices, unit spacing
  for (Eigen::Vector3f& v : m.vertices) v *= 0.1f;
  // keep y within [0, 1]
  std::vector<Triangle> kept;
  for (const Triangle& t : m.triangles) {
    bool inside = true;
    for (std::uint32_t v : t) inside &= m.vertices[v].y() <= 1.0f + 1e-6f;
    if (inside) kept.push_back(t);
  }
  return compact_vertices(m, kept);
}

TEST(RimTrim, PeelsTheBorderBackToWithinTheLimitOfTheData) {
  const std::vector<Eigen::Vector3f> points = square_points();
  const KdTreeIndex index(points);
  const TriangleMesh mesh = long_grid();
  std::size_t removed = 0;
  const TriangleMesh out = trim_rim(mesh, points, index, 0.25f, &removed);
  EXPECT_GT(removed, 0u);
  EXPECT_EQ(out.triangles.size(), mesh.triangles.size() - removed);
  float farthest = 0.0f, reach = 0.0f;
  for (const Eigen::Vector3f& v : out.vertices) {
    farthest = std::max(farthest, v.x() - 1.0f);
    reach = std::max(reach, v.x());
  }
  EXPECT_LE(farthest, 0.25f + 1e-5f) << "no vertex beyond the limit";
  EXPECT_GE(reach, 1.2f - 1e-5f) << "what is within the limit stays";
  for (const Triangle& t : out.triangles)
    for (std::uint32_t v : t) ASSERT_LT(v, out.vertices.size());
}

TEST(RimTrim, GivenVerdictsPeelExactlyAsMeasuredOnes) {
  const std::vector<Eigen::Vector3f> points = square_points();
  const KdTreeIndex index(points);
  const TriangleMesh mesh = long_grid();
  std::size_t measured_removed = 0, given_removed = 0;
  const TriangleMesh measured = trim_rim(mesh, points, index, 0.25f, &measured_removed);
  const std::vector<std::uint8_t> beyond =
      vertices_beyond_data(mesh.vertices, points, index, 0.25f);
  ASSERT_EQ(beyond.size(), mesh.vertices.size());
  const TriangleMesh given = trim_rim(mesh, beyond, &given_removed);
  EXPECT_GT(measured_removed, 0u);
  EXPECT_EQ(given_removed, measured_removed);
  EXPECT_EQ(given.vertices, measured.vertices);
  EXPECT_EQ(given.triangles, measured.triangles);
}

TEST(RimTrim, ClosedMeshesAndBordersOnTheDataAreUnchanged) {
  const TriangleMesh tet = test::tetrahedron();
  const KdTreeIndex far_index(tet.vertices);
  std::size_t removed = 7;
  EXPECT_EQ(trim_rim(tet, tet.vertices, far_index, 1e-3f, &removed).triangles, tet.triangles);
  EXPECT_EQ(removed, 0u);
  const std::vector<Eigen::Vector3f> points = square_points();
  const KdTreeIndex index(points);
  TriangleMesh square = test::grid_mesh(11);
  for (Eigen::Vector3f& v : square.vertices) v *= 0.1f;
  EXPECT_EQ(trim_rim(square, points, index, 0.05f, &removed).triangles.size(),
            square.triangles.size());
  EXPECT_EQ(removed, 0u);
}

TEST(RimTrim, SparseDataAllowTwiceTheirSpacing) {
  // Points every 0.5 along the square's border: a rim vertex 0.4 from them is within twice
  // their spacing, so a limit of 0.1 does not eat the mesh between sparse points.
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i <= 6; ++i) points.emplace_back(0.5f * i, 0.0f, 0.0f);
  for (int i = 0; i <= 6; ++i) points.emplace_back(0.5f * i, 1.0f, 0.0f);
  const KdTreeIndex index(points);
  const TriangleMesh mesh = long_grid();
  std::size_t removed = 0;
  trim_rim(mesh, points, index, 0.1f, &removed);
  EXPECT_EQ(removed, 0u);
}

}  // namespace
}  // namespace meshflow
