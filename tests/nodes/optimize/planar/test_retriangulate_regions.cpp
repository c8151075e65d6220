#include "nodes/optimize/planar/retriangulate_regions.h"

#include <gtest/gtest.h>

#include <cstdio>

#include "fixtures/mesh_fixtures.h"
#include "fixtures/room_fixture.h"
#include "nodes/eval/completeness.h"
#include "nodes/optimize/planar/planar_regions.h"
#include "nodes/optimize/planar/sharp_edges.h"
#include "runtime/half_edge_mesh.h"
#include "test_support.h"

namespace meshflow {
namespace {

double total_area(const TriangleMesh& m) {
  double area = 0.0;
  for (const Triangle& t : m.triangles)
    area += 0.5 * static_cast<double>((m.vertices[t[1]] - m.vertices[t[0]])
                                          .cross(m.vertices[t[2]] - m.vertices[t[0]])
                                          .norm());
  return area;
}

TriangleMesh retriangulated(const TriangleMesh& m, RetriangulationReport& report,
                            const RetriangulationConfig& config = {}) {
  const PlanarSegmentation s = grow_planar_regions(HalfEdgeMesh(m));
  return retriangulate_regions(m, s, config, &report);
}

TEST(RetriangulateRegions, AFlatSheetWithAHoleBecomesItsEightCornersAndKeepsItsArea) {
  const TriangleMesh m = test::without_faces(test::grid_mesh(20), [](const Eigen::Vector3f& c) {
    return c.x() > 6 && c.x() < 10 && c.y() > 6 && c.y() < 10;
  });
  RetriangulationReport report;
  const TriangleMesh out = retriangulated(m, report);
  EXPECT_EQ(report.regions, 1u);
  EXPECT_EQ(report.retriangulated, 1u);
  EXPECT_EQ(report.contour_vertices, 4u * 19u + 16u);
  EXPECT_EQ(report.dropped_contour_vertices, report.contour_vertices - 8u);
  EXPECT_EQ(out.vertices.size(), 8u);
  EXPECT_EQ(out.triangles.size(), 8u);  // 8 vertices + 2 x 1 hole - 2
  EXPECT_NEAR(total_area(out), 19.0 * 19.0 - 16.0, 1e-3);
  const HalfEdgeMesh h(out);
  EXPECT_EQ(h.check(), "");
  EXPECT_EQ(h.border_loops().size(), 2u);
  for (const Triangle& t : out.triangles) EXPECT_GT(face_normal(out, t).z(), 0.999f);
}

TEST(RetriangulateRegions, NeighbouringRegionsShareTheirSimplifiedBoundary) {
  // The bend along x = 0 is a contour chain shared by both planes.
  const TriangleMesh m = test::bent_sheet();
  RetriangulationReport report;
  const TriangleMesh out = retriangulated(m, report);
  EXPECT_EQ(report.retriangulated, 2u);
  EXPECT_EQ(out.vertices.size(), 6u);  // the four corners and the two ends of the bend
  EXPECT_EQ(out.triangles.size(), 4u);
  const EdgeStatistics edges = edge_statistics(out);
  EXPECT_EQ(edges.non_manifold_edges, 0u);
  EXPECT_EQ(edges.inconsistent_edges, 0u);
  EXPECT_EQ(edges.boundary_edges, 6u);  // one outline: the bend is an interior edge
  EXPECT_NEAR(total_area(out), total_area(m), 1e-4);
}

TEST(RetriangulateRegions, RoomRegionsShrinkWithinTheContourTolerance) {
  const TriangleMesh& in = test::room_mesh();
  RetriangulationConfig config;
  config.contour_tolerance = 0.5f * test::kRoomVoxel;
  RetriangulationReport report;
  const TriangleMesh out = retriangulated(in, report, config);
  const double hausdorff = hausdorff_distance(out, in);
  std::printf(
      "[ retriangulate ] %zu -> %zu triangles; %zu of %zu regions, %zu of %zu contour vertices "
      "dropped (max deviation %.4f m); Hausdorff %.4f m\n",
      in.triangles.size(), out.triangles.size(), report.retriangulated, report.regions,
      report.dropped_contour_vertices, report.contour_vertices, report.max_contour_deviation,
      hausdorff);
  EXPECT_GE(report.retriangulated, report.regions * 3 / 4);
  EXPECT_LT(out.triangles.size(), in.triangles.size() / 2);
  EXPECT_LE(report.max_contour_deviation, config.contour_tolerance);
  // (Feature corners stay, and contour vertices off their region's plane keep their faces:
  // 2 069 of 9 860 dropped, 2 762 of 10 912 before.)
  EXPECT_GT(report.dropped_contour_vertices, report.contour_vertices / 5);
  EXPECT_LT(hausdorff, 2.0 * config.contour_tolerance);
  EXPECT_EQ(test::half_edge_problem(out), "");
  EXPECT_EQ(edge_statistics(out).non_manifold_edges, 0u);
  EXPECT_EQ(edge_statistics(out).inconsistent_edges, 0u);
}

TEST(RetriangulateRegions, AfterSharpeningEveryRoomRegionIsRetriangulated) {
  // Cutting creases can leave a few faces of a region folded over in its plane (a contour
  // loop running the wrong way); the region repairs that instead of staying as it was.
  const TriangleMesh& in = test::room_mesh();
  const TriangleMesh sharp = sharpen_creases(in, grow_planar_regions(HalfEdgeMesh(in)));
  RetriangulationReport report;
  const TriangleMesh out = retriangulated(sharp, report);
  std::printf("[ retriangulate ] after sharpen: %zu -> %zu triangles, %zu of %zu regions\n",
              sharp.triangles.size(), out.triangles.size(), report.retriangulated, report.regions);
  EXPECT_EQ(report.retriangulated, report.regions);
  EXPECT_LT(out.triangles.size(), sharp.triangles.size() / 10);
  EXPECT_EQ(test::half_edge_problem(out), "");
  EXPECT_EQ(edge_statistics(out).non_manifold_edges, 0u);
}

TEST(RetriangulateRegions, SameMeshWithOneAndTwoThreads) {
  auto run = [] {
    RetriangulationReport report;
    return retriangulated(test::room_mesh(), report);
  };
  const TriangleMesh one = test::with_threads(1, run), two = test::with_threads(2, run);
  EXPECT_GT(one.triangles.size(), 100u);
  EXPECT_EQ(one.triangles, two.triangles);
  EXPECT_EQ(one.vertices, two.vertices);
}

}  // namespace
}  // namespace meshflow
