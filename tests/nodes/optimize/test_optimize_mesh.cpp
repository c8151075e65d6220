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

namespace meshflow {
namespace {

// A flat 6 x 6 grid of unit quads with the quad at (2, 2) missing (a 4-edge hole), plus a lone
// triangle far off (a component of 1) and a second fan at grid vertex (5, 5) (a bow tie).
TriangleMesh grid_with_hole_and_debris() {
  TriangleMesh m;
  const auto id = [](int x, int y) { return static_cast<std::uint32_t>(y * 7 + x); };
  for (int y = 0; y <= 6; ++y)
    for (int x = 0; x <= 6; ++x) m.vertices.emplace_back(x, y, 0.0f);
  for (int y = 0; y < 6; ++y)
    for (int x = 0; x < 6; ++x) {
      if (x == 2 && y == 2) continue;
      m.triangles.push_back({id(x, y), id(x + 1, y), id(x + 1, y + 1)});
      m.triangles.push_back({id(x, y), id(x + 1, y + 1), id(x, y + 1)});
    }
  const auto lone = static_cast<std::uint32_t>(m.vertices.size());
  m.vertices.insert(m.vertices.end(), {{20, 20, 0}, {21, 20, 0}, {20, 21, 0}});
  m.triangles.push_back({lone, lone + 1, lone + 2});
  const auto fan = static_cast<std::uint32_t>(m.vertices.size());  // touches (6, 6) only
  m.vertices.insert(m.vertices.end(), {{7, 6, 1}, {6, 7, 1}});
  m.triangles.push_back({id(6, 6), fan, fan + 1});
  return m;
}

// Held vertices (a chunk's seam) keep what goes on beyond them: the hole through one stays
// open, the component holding one stays, the vertex keeps its second fan. Without them the
// steps do what they always do; the flags follow the vertices.
TEST(OptimizeMesh, HeldVerticesKeepTheirLoopsComponentsAndFans) {
  const TriangleMesh m = grid_with_hole_and_debris();
  OptimizeConfig config;  // clean, holes
  config.feature_angle_deg = 180.0f;
  const TriangleMesh free = optimize_mesh(m, config);
  EXPECT_EQ(free.triangles.size(), 72u) << "70 of the grid + 2 filling the hole";
  EXPECT_EQ(free.vertices.size(), 49u) << "the lone triangle and the second fan removed";

  HeldVertices held;
  held.flags.assign(m.vertices.size(), 0);
  held.flags[2 * 7 + 2] = 1;              // a corner of the hole
  held.flags[m.vertices.size() - 5] = 1;  // the lone triangle's first corner
  held.flags[6 * 7 + 6] = 1;              // the bow tie's vertex
  held.flags[m.vertices.size() - 1] = 4;  // an unheld flag that must follow its vertex
  OptimizeReport report;
  const TriangleMesh kept = optimize_mesh(m, config, &report, held);
  EXPECT_EQ(kept.triangles, m.triangles) << "nothing removed, nothing filled";
  EXPECT_EQ(kept.vertices.size(), m.vertices.size());
  ASSERT_EQ(held.flags.size(), kept.vertices.size());
  for (std::size_t v = 0; v < kept.vertices.size(); ++v) {
    const Eigen::Vector3f& p = kept.vertices[v];
    const std::uint8_t expected = p == Eigen::Vector3f(2, 2, 0)     ? 1
                                  : p == Eigen::Vector3f(20, 20, 0) ? 1
                                  : p == Eigen::Vector3f(6, 6, 0)   ? 1
                                  : p == Eigen::Vector3f(6, 7, 1)   ? 4
                                                                    : 0;
    EXPECT_EQ(held.flags[v], expected) << v;
  }
  ASSERT_EQ(report.steps.size(), 2u);
  EXPECT_NE(report.steps[1].detail.find("1 through held"), std::string::npos)
      << report.steps[1].detail;

  OptimizeConfig decimate = config;
  decimate.steps.push_back(OptimizeStep::kDecimate);
  HeldVertices again{std::vector<std::uint8_t>(m.vertices.size(), 0), 1};
  EXPECT_THROW(optimize_mesh(m, decimate, nullptr, again), Error) << "decimation cannot hold";
}

}  // namespace
}  // namespace meshflow
