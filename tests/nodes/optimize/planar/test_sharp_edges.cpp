#include "nodes/optimize/planar/sharp_edges.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <unordered_map>

#include "fixtures/mesh_fixtures.h"
#include "fixtures/room_fixture.h"
#include "nodes/eval/surface_eval.h"
#include "nodes/optimize/planar/planar_regions.h"
#include "nodes/search/mesh_distance_index.h"
#include "runtime/half_edge_mesh.h"
#include "runtime/voxel_key.h"
#include "test_support.h"

namespace meshflow {
namespace {

struct Segment {
  Eigen::Vector3f a, b;
};

// The edges of an axis-aligned box (centre c, half sizes h).
std::vector<Segment> box_edges(const Eigen::Vector3f& c, const Eigen::Vector3f& h) {
  std::vector<Segment> out;
  for (int axis = 0; axis < 3; ++axis)
    for (int s1 = -1; s1 <= 1; s1 += 2)
      for (int s2 = -1; s2 <= 1; s2 += 2) {
        Eigen::Vector3f a = c, b = c;
        const int u = (axis + 1) % 3, w = (axis + 2) % 3;
        a[u] = b[u] = c[u] + static_cast<float>(s1) * h[u];
        a[w] = b[w] = c[w] + static_cast<float>(s2) * h[w];
        a[axis] -= h[axis];
        b[axis] += h[axis];
        out.push_back({a, b});
      }
  return out;
}

// Distances to `mesh` from points every centimetre along the axis-aligned `edges` (ends
// excluded by `margin`) where the scan saw both faces of the edge: `scanned` has vertices
// within `reach` of the point on each face's plane (within reach / 8) and at least 0.3 reach from
// the other plane. Where one face was occluded there is no crease to recover.
std::vector<float> edge_distances(const std::vector<Segment>& edges, const TriangleMesh& scanned,
                                  const TriangleMesh& mesh, float margin, float reach) {
  std::unordered_map<VoxelKey, std::vector<Eigen::Vector3f>> cells;
  for (const Eigen::Vector3f& v : scanned.vertices) cells[pack_key(cell_of(v, reach))].push_back(v);
  const MeshDistanceIndex index(mesh);
  std::vector<float> out;
  for (const Segment& s : edges) {
    int axis = 0;
    (s.b - s.a).cwiseAbs().maxCoeff(&axis);
    const int u = (axis + 1) % 3, w = (axis + 2) % 3;
    const float length = (s.b - s.a).norm();
    for (float t = margin; t <= length - margin; t += 0.01f) {
      const Eigen::Vector3f p = s.a + (s.b - s.a) * (t / length);
      bool on_u = false, on_w = false;
      const Eigen::Vector3i c = cell_of(p, reach);
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            const auto cell = cells.find(pack_key(c + Eigen::Vector3i(dx, dy, dz)));
            if (cell == cells.end()) continue;
            for (const Eigen::Vector3f& v : cell->second) {
              if ((v - p).norm() > reach) continue;
              const float du = std::abs(v[u] - p[u]), dw = std::abs(v[w] - p[w]);
              on_u = on_u || (du < 0.125f * reach && dw > 0.3f * reach);
              on_w = on_w || (dw < 0.125f * reach && du > 0.3f * reach);
            }
          }
      if (on_u && on_w) out.push_back(index.closest(p).distance);
    }
  }
  return out;
}

TEST(SharpEdges, ABevelledCreaseBecomesSharp) {
  // The bent sheet with its crease vertices lifted 3 cm off the line, as marching cubes bevels
  // a crease; sharpening must put them back on the line x = 0, z = 0.
  auto crease = [](float x) { return x > 0 ? x : 0.0f; };
  const TriangleMesh bevelled =
      test::profile_sheet([&](float x) { return std::abs(x) < 1e-4f ? 0.03f : crease(x); });
  SharpEdgeReport report;
  const TriangleMesh out =
      sharpen_creases(bevelled, grow_planar_regions(HalfEdgeMesh(bevelled)), {}, &report);
  EXPECT_EQ(report.creases, 1u);
  EXPECT_EQ(report.to_line, 10u);
  EXPECT_EQ(report.flipped_faces, 0u);
  ASSERT_EQ(out.vertices.size(), bevelled.vertices.size());
  ASSERT_EQ(out.triangles, bevelled.triangles);
  for (const Eigen::Vector3f& v : out.vertices) EXPECT_NEAR(v.z(), crease(v.x()), 1e-5f);
}

TEST(SharpEdges, CutsTheBevelAlongTheLine) {
  // Crease vertices moved half-way across the bevel (along the sheet) so that no end is near
  // the line: every bevel edge must be cut there, and the line covered end to end.
  auto crease = [](float x) { return x > 0 ? x : 0.0f; };
  TriangleMesh bevelled = test::profile_sheet(crease);
  for (Eigen::Vector3f& v : bevelled.vertices)
    if (std::abs(v.x()) < 1e-4f) v = Eigen::Vector3f(0.04f, v.y(), 0.01f);
  SharpEdgeReport report;
  const TriangleMesh out =
      sharpen_creases(bevelled, grow_planar_regions(HalfEdgeMesh(bevelled)), {}, &report);
  EXPECT_EQ(test::half_edge_problem(out), "");
  EXPECT_EQ(report.flipped_faces, 0u);
  EXPECT_GT(report.split_edges, 0u);
  for (const Eigen::Vector3f& v : out.vertices) EXPECT_NEAR(v.z(), crease(v.x()), 1e-5f);
  const MeshDistanceIndex index(out);
  for (float y = 0.0f; y <= 0.9f; y += 0.01f)
    EXPECT_LT(index.closest(Eigen::Vector3f(0.0f, y, 0.0f)).distance, 1e-5f) << y;
}

TEST(SharpEdges, RoomCreasesComeWithinATenthOfAVoxel) {
  const TriangleMesh& in = test::room_mesh();
  const PlanarSegmentation s = grow_planar_regions(HalfEdgeMesh(in));
  SharpEdgeReport report;
  const TriangleMesh out = sharpen_creases(in, s, {}, &report);
  std::printf(
      "[ sharpen ] %zu creases: %zu to planes, %zu to lines, %zu to corners, %zu cuts, %zu "
      "flipped, line distance %.2g\n",
      report.creases, report.to_plane, report.to_line, report.to_corner, report.split_edges,
      report.flipped_faces, report.max_line_distance);
  const float voxel = test::kRoomVoxel;
  const std::vector<Segment> room = box_edges({0.0f, 0.0f, 1.5f}, {4.0f, 3.0f, 1.5f});
  const std::vector<Segment> table = box_edges({1.8f, 0.8f, 0.375f}, {0.6f, 0.4f, 0.375f});
  // The true creases: the room's twelve edges and the table-sized block's (ends excluded,
  // where three planes meet and the scan thins out), where the scan saw both faces.
  for (const auto& [name, edges] : {std::pair{"room", room}, std::pair{"table", table}}) {
    const std::vector<float> after_distances = edge_distances(edges, in, out, 2 * voxel, 2 * voxel);
    const DistanceStats before =
        distance_stats(edge_distances(edges, in, in, 2 * voxel, 2 * voxel));
    const DistanceStats after = distance_stats(after_distances);
    std::size_t within = 0;
    for (float d : after_distances) within += d <= 0.1f * voxel ? 1 : 0;
    std::printf(
        "[ sharpen ] %s edges (%zu points): mean %.4f -> %.4f, p95 %.4f -> %.4f, max %.4f -> "
        "%.4f m; %.1f %% within 0.1 voxel\n",
        name, after.samples, before.mean, after.mean, before.p95, after.p95, before.max, after.max,
        100.0 * static_cast<double>(within) / static_cast<double>(after.samples));
    EXPECT_GT(after.samples, 300u) << name;
    EXPECT_GT(before.mean, 0.3 * voxel) << name;  // marching cubes bevelled them
    EXPECT_LT(after.mean, 0.1 * voxel) << name;
    EXPECT_LT(after.p95, 0.1 * voxel) << name;
    EXPECT_GT(within, after.samples * 95 / 100) << name;
  }
  EXPECT_GE(report.creases, 20u);  // 12 room edges and the visible ones of the two blocks
  EXPECT_LE(mesh_topology(out).degenerate_faces, mesh_topology(in).degenerate_faces);
  const HalfEdgeMesh h(out);
  EXPECT_EQ(h.check(), "");
  EXPECT_EQ(report.flipped_faces, 0u);
}

TEST(SharpEdges, SameMeshWithOneAndTwoThreads) {
  const TriangleMesh& in = test::room_mesh();
  const PlanarSegmentation s = grow_planar_regions(HalfEdgeMesh(in));
  const TriangleMesh one = test::with_threads(1, [&] { return sharpen_creases(in, s); });
  const TriangleMesh two = test::with_threads(2, [&] { return sharpen_creases(in, s); });
  EXPECT_GT(one.triangles.size(), 100u);
  EXPECT_EQ(one.triangles, two.triangles);
  EXPECT_EQ(one.vertices, two.vertices);
}

}  // namespace
}  // namespace meshflow
