#include "nodes/optimize/optimize_mesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "fixtures/mesh_fixtures.h"
#include "fixtures/room_fixture.h"
#include "nodes/eval/completeness.h"
#include "runtime/error.h"
#include "runtime/half_edge_mesh.h"
#include "test_support.h"

namespace meshflow {
namespace {

// Manifold, consistently oriented, no face without area, no face twice.
void expect_valid(const TriangleMesh& m, const char* step) {
  SCOPED_TRACE(step);
  const EdgeStatistics e = edge_statistics(m);
  EXPECT_EQ(e.non_manifold_edges, 0u);
  EXPECT_EQ(e.inconsistent_edges, 0u);
  EXPECT_EQ(test::half_edge_problem(m), "");
  std::vector<Triangle> sorted;
  for (const Triangle& t : m.triangles) {
    EXPECT_GT((m.vertices[t[1]] - m.vertices[t[0]])
                  .cross(m.vertices[t[2]] - m.vertices[t[0]])
                  .squaredNorm(),
              0.0f);
    Triangle s = t;
    std::sort(s.begin(), s.end());
    sorted.push_back(s);
  }
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end());
}

TEST(OptimizeMesh, ParsesStepLists) {
  EXPECT_EQ(parse_optimize_steps("default"), OptimizeConfig{}.steps);
  EXPECT_TRUE(parse_optimize_steps("none").empty());
  EXPECT_EQ(parse_optimize_steps("planes,clean,decimate"),
            (std::vector<OptimizeStep>{OptimizeStep::kPlanes, OptimizeStep::kClean,
                                       OptimizeStep::kDecimate}));
  try {
    parse_optimize_steps("clean,smooth");
    FAIL() << "an unknown step was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("'smooth'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("decimate"), std::string::npos) << e.what();
  }
}

TEST(OptimizeMesh, EveryStepLeavesTheRoomValidAndDecimationStaysClose) {
  TriangleMesh mesh = test::room_mesh();
  expect_valid(mesh, "input");
  TriangleMesh planar;
  for (OptimizeStep step :
       parse_optimize_steps("clean,holes,planes,sharpen,retriangulate,remesh,decimate")) {
    OptimizeConfig config;
    config.steps = {step};
    OptimizeReport report;
    mesh = optimize_mesh(mesh, config, &report);
    if (step == OptimizeStep::kPlanes) planar = mesh;
    ASSERT_EQ(report.steps.size(), 1u);
    EXPECT_FALSE(report.steps[0].skipped) << report.steps[0].detail;
    EXPECT_EQ(report.steps[0].triangles_out, mesh.triangles.size());
    std::printf("[ optimize ]%s", format_optimize_report(report).c_str());
    expect_valid(mesh, optimize_step_name(step));
    EXPECT_EQ(mesh.normals.size(), mesh.vertices.size());  // the pipeline's normals follow
  }
  // Decimation of the planar mesh to 25 % keeps every vertex within half a voxel of it.
  OptimizeConfig decimate;
  decimate.steps = {OptimizeStep::kDecimate};
  const TriangleMesh decimated = optimize_mesh(planar, decimate);
  EXPECT_LE(decimated.triangles.size(), planar.triangles.size() / 4 + 1);
  const double hausdorff = hausdorff_distance(decimated, planar);
  std::printf("[ optimize ] decimated to %zu of %zu triangles, Hausdorff %.4f m\n",
              decimated.triangles.size(), planar.triangles.size(), hausdorff);
  EXPECT_LT(hausdorff, 0.5 * test::kRoomVoxel);
}

TEST(OptimizeMesh, NonManifoldInputSkipsThePlanarStepsWithTheReason) {
  // Three triangles on one edge (0-1): clean, holes and decimate run, the half-edge steps pass
  // it on.
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  m.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  OptimizeConfig config;
  config.cleanup.min_component_triangles = 0;
  config.steps = parse_optimize_steps("clean,holes,planes,sharpen,retriangulate,remesh,decimate");
  OptimizeReport report;
  const TriangleMesh out = optimize_mesh(m, config, &report);
  EXPECT_EQ(out.triangles, m.triangles);
  ASSERT_EQ(report.steps.size(), 7u);
  EXPECT_FALSE(report.steps[0].skipped);
  EXPECT_FALSE(report.steps[1].skipped);  // holes: the loops through vertex 1 are ambiguous
  EXPECT_NE(report.steps[1].detail.find("not fillable"), std::string::npos)
      << report.steps[1].detail;
  EXPECT_TRUE(report.steps[2].skipped);
  EXPECT_TRUE(report.steps[3].skipped);
  EXPECT_TRUE(report.steps[4].skipped);
  EXPECT_TRUE(report.steps[5].skipped);
  EXPECT_FALSE(report.steps[6].skipped);  // QEM refuses the collapses it cannot make
  EXPECT_NE(report.steps[2].detail.find("skipped"), std::string::npos);
  EXPECT_NE(report.steps[2].detail.find("edge"), std::string::npos) << report.steps[2].detail;
}

TEST(OptimizeMesh, SameMeshWithOneAndTwoThreads) {
  OptimizeConfig config;
  config.steps = parse_optimize_steps("clean,holes,planes,sharpen,retriangulate,remesh,decimate");
  auto run = [&] { return optimize_mesh(test::room_mesh(), config); };
  const TriangleMesh one = test::with_threads(1, run), two = test::with_threads(2, run);
  EXPECT_GT(one.triangles.size(), 100u);
  EXPECT_EQ(one.triangles, two.triangles);
  EXPECT_EQ(one.vertices, two.vertices);
}

}  // namespace
}  // namespace meshflow
