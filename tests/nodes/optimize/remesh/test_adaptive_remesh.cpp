#include "nodes/optimize/remesh/adaptive_remesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "fixtures/mesh_fixtures.h"
#include "fixtures/room_fixture.h"
#include "nodes/search/mesh_distance_index.h"
#include "test_support.h"

namespace meshflow {
namespace {

// A flat 2 x 2 m sheet with a Gaussian bump 20 cm high (sigma 15 cm) in the middle, sampled
// every 2 cm: flat almost everywhere, curved (up to 8.9 / m) on the bump.
constexpr float kBumpHeight = 0.2f, kBumpSigma = 0.15f, kSpacing = 0.02f;

float bump(float x, float y) {
  return kBumpHeight * std::exp(-(x * x + y * y) / (2.0f * kBumpSigma * kBumpSigma));
}

TriangleMesh bump_sheet() {
  TriangleMesh m = test::grid_mesh(101);
  for (Eigen::Vector3f& v : m.vertices) {
    v.x() = v.x() * kSpacing - 1.0f;
    v.y() = v.y() * kSpacing - 1.0f;
    v.z() = bump(v.x(), v.y());
  }
  return m;
}

float radius(const Eigen::Vector3f& p) { return std::hypot(p.x(), p.y()); }

TEST(AdaptiveRemesh, ABumpOnAPlaneKeepsItsVerticesWhereItBends) {
  const TriangleMesh in = bump_sheet();
  AdaptiveRemeshConfig config;
  config.tolerance = 0.002f;
  AdaptiveRemeshReport report;
  const TriangleMesh out = adaptive_remesh(in, config, &report);
  std::printf(
      "bump: %zu -> %zu vertices, %zu splits, %zu collapses, %zu flips, targets %.3f-%.3f\n",
      report.vertices_in, report.vertices_out, report.splits, report.collapses, report.flips,
      report.min_target, report.max_target);
  EXPECT_EQ(test::half_edge_problem(out), "");
  EXPECT_LT(out.vertices.size(), in.vertices.size() / 4);

  // Density: vertices per square metre on the bump (r < 0.25 m) against the flat part
  // (r > 0.7 m), both in the xy projection.
  std::size_t on_bump = 0, on_flat = 0;
  for (const Eigen::Vector3f& v : out.vertices) {
    on_bump += radius(v) < 0.25f ? 1 : 0;
    on_flat += radius(v) > 0.7f ? 1 : 0;
  }
  const float bump_area = static_cast<float>(M_PI) * 0.25f * 0.25f;
  const float flat_area = 4.0f - static_cast<float>(M_PI) * 0.7f * 0.7f;
  const float density_ratio =
      (static_cast<float>(on_bump) / bump_area) / (static_cast<float>(on_flat) / flat_area);
  std::printf("bump: %zu vertices on the bump, %zu on the flat part, density ratio %.1f\n", on_bump,
              on_flat, density_ratio);
  EXPECT_GT(density_ratio, 10.0f);

  // Accuracy, both ways: every output vertex, edge midpoint and face centroid lies within the
  // tolerance of the true surface (measured vertically, which overestimates on slopes), and
  // every point of the true surface lies within the tolerance of the output.
  float worst_out = 0.0f;
  for (const Triangle& t : out.triangles) {
    const Eigen::Vector3f& a = out.vertices[t[0]];
    const Eigen::Vector3f& b = out.vertices[t[1]];
    const Eigen::Vector3f& c = out.vertices[t[2]];
    for (const Eigen::Vector3f& p :
         {a, Eigen::Vector3f(0.5f * (a + b)), Eigen::Vector3f(0.5f * (b + c)),
          Eigen::Vector3f(0.5f * (c + a)), Eigen::Vector3f((a + b + c) / 3.0f)})
      worst_out = std::max(worst_out, std::abs(p.z() - bump(p.x(), p.y())));
  }
  const MeshDistanceIndex index(out);
  float worst_in = 0.0f;
  for (float y = -0.99f; y < 0.99f; y += 0.005f)
    for (float x = -0.99f; x < 0.99f; x += 0.005f)
      worst_in = std::max(worst_in, index.closest({x, y, bump(x, y)}).distance);
  std::printf("bump: output off the surface by at most %.4f m, surface off the output by %.4f m\n",
              worst_out, worst_in);
  EXPECT_LT(worst_out, 1.5f * config.tolerance);
  EXPECT_LT(worst_in, 1.5f * config.tolerance);

  // The outline is kept: the four corners are still there and the projected area is 4 m^2.
  float area = 0.0f;
  for (const Triangle& t : out.triangles) {
    const Eigen::Vector3f ab = out.vertices[t[1]] - out.vertices[t[0]];
    const Eigen::Vector3f ac = out.vertices[t[2]] - out.vertices[t[0]];
    area += 0.5f * (ab.x() * ac.y() - ab.y() * ac.x());
  }
  EXPECT_NEAR(area, 4.0f, 1e-3f);
  for (const Eigen::Vector3f& corner : {Eigen::Vector3f(-1, -1, 0), Eigen::Vector3f(1, -1, 0),
                                        Eigen::Vector3f(1, 1, 0), Eigen::Vector3f(-1, 1, 0)})
    EXPECT_TRUE(std::any_of(out.vertices.begin(), out.vertices.end(),
                            [&](const Eigen::Vector3f& v) { return (v - corner).norm() < 1e-4f; }));
}

TEST(AdaptiveRemesh, ASparseCurvedMeshIsRefined) {
  // The bump sampled every 10 cm is too coarse for a 0.5 mm tolerance: the remesher splits
  // its long edges on the bump (more vertices there), and keeps the flat part coarse.
  TriangleMesh in = test::grid_mesh(21);
  for (Eigen::Vector3f& v : in.vertices) {
    v.x() = v.x() * 0.1f - 1.0f;
    v.y() = v.y() * 0.1f - 1.0f;
    v.z() = bump(v.x(), v.y());
  }
  AdaptiveRemeshConfig config;
  config.tolerance = 0.0005f;
  config.min_edge = 0.02f;
  config.max_edge = 0.2f;
  AdaptiveRemeshReport report;
  const TriangleMesh out = adaptive_remesh(in, config, &report);
  EXPECT_EQ(test::half_edge_problem(out), "");
  EXPECT_GT(report.splits, 0u);
  auto count_within = [](const TriangleMesh& m, float r) {
    return std::count_if(m.vertices.begin(), m.vertices.end(),
                         [&](const Eigen::Vector3f& v) { return radius(v) < r; });
  };
  EXPECT_GT(count_within(out, 0.3f), 2 * count_within(in, 0.3f));
}

TEST(AdaptiveRemesh, TheRoomLosesMostVerticesAndStaysClose) {
  const TriangleMesh& in = test::room_mesh();
  AdaptiveRemeshReport report;
  // The noise-free room's default tolerance is its floor (0.01 median edge); a scan's is about
  // a quarter of the median edge: remesh the room at that.
  AdaptiveRemeshConfig config;
  config.tolerance = 0.25f * median_edge_length(in);
  const TriangleMesh out = adaptive_remesh(in, config, &report);
  EXPECT_EQ(test::half_edge_problem(out), "");
  const MeshDistanceIndex index(out);
  std::vector<float> d;
  for (const Eigen::Vector3f& v : in.vertices) d.push_back(index.closest(v).distance);
  std::sort(d.begin(), d.end());
  double mean = 0.0;
  for (float x : d) mean += x;
  mean /= static_cast<double>(d.size());
  const float p95 = d[d.size() * 95 / 100];
  std::printf(
      "room: %zu -> %zu vertices (%zu -> %zu triangles), tolerance %.4f m, input off the "
      "output: mean %.4f m, p95 %.4f m, max %.4f m\n",
      report.vertices_in, report.vertices_out, in.triangles.size(), out.triangles.size(),
      report.tolerance, mean, p95, d.back());
  EXPECT_LT(out.vertices.size(), in.vertices.size() / 2);
  EXPECT_LT(mean, 0.5 * report.tolerance);
  EXPECT_LT(p95, 2.0f * report.tolerance);
}

TEST(AdaptiveRemesh, SameMeshWithOneAndTwoThreads) {
  const TriangleMesh& in = test::room_mesh();
  const TriangleMesh one = test::with_threads(1, [&] { return adaptive_remesh(in); });
  const TriangleMesh two = test::with_threads(2, [&] { return adaptive_remesh(in); });
  EXPECT_GT(one.triangles.size(), 100u);
  EXPECT_EQ(one.triangles, two.triangles);
  EXPECT_EQ(one.vertices, two.vertices);
}

}  // namespace
}  // namespace meshflow
