#include "nodes/optimize/features.h"

#include <gtest/gtest.h>

#include <map>

#include "nodes/decimate/qem_decimation.h"

namespace meshflow {
namespace {

// The unit cube [0, 1]^3 with each face an n x n grid of squares cut into two triangles
// (alternating diagonals), vertices shared, faces wound outward.
TriangleMesh tessellated_cube(int n) {
  TriangleMesh m;
  std::map<std::array<int, 3>, std::uint32_t> index;
  auto vertex = [&](const std::array<int, 3>& g) {
    const auto [it, added] = index.emplace(g, static_cast<std::uint32_t>(m.vertices.size()));
    if (added)
      m.vertices.emplace_back(static_cast<float>(g[0]) / static_cast<float>(n),
                              static_cast<float>(g[1]) / static_cast<float>(n),
                              static_cast<float>(g[2]) / static_cast<float>(n));
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, w = (axis + 2) % 3;
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          std::array<std::uint32_t, 4> q;
          const int di[4] = {0, 1, 1, 0}, dj[4] = {0, 0, 1, 1};
          for (int k = 0; k < 4; ++k) {
            std::array<int, 3> g;
            g[axis] = side * n;
            g[u] = i + di[k];
            g[w] = j + dj[k];
            q[k] = vertex(g);
          }
          // (u, w, axis) is right-handed: counter-clockwise in (u, w) faces +axis.
          Triangle a{q[0], q[1], q[2]}, b{q[0], q[2], q[3]};
          if ((i + j) % 2 == 1) a = {q[0], q[1], q[3]}, b = {q[1], q[2], q[3]};
          if (side == 0) std::swap(a[1], a[2]), std::swap(b[1], b[2]);
          m.triangles.push_back(a);
          m.triangles.push_back(b);
        }
    }
  return m;
}

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
  const MeshFeatures kept = detect_features(out);
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

}  // namespace
}  // namespace meshflow
