#include "nodes/extract/planar_marching_cubes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "fixtures/solid_fixture.h"
#include "nodes/distance/hoppe_distance.h"
#include "nodes/eval/surface_eval.h"
#include "nodes/voxelize/voxelize.h"
#include "runtime/threads.h"

namespace meshflow {
namespace {

constexpr float kPlanarVoxel = 0.05f;
constexpr float kHeight = 0.0123f;  // off the lattice planes

// Distance from (x, y) to the boundary of the axis-aligned rectangle [lo, hi].
float to_rectangle_outline(const Eigen::Vector2f& q, const Eigen::Vector2f& lo,
                           const Eigen::Vector2f& hi) {
  const Eigen::Vector2f c = (lo + hi) / 2, h = (hi - lo) / 2;
  const Eigen::Vector2f d = (q - c).cwiseAbs() - h;
  return std::abs(d.cwiseMax(0.0f).norm() + std::min(d.maxCoeff(), 0.0f));
}

struct HoledPatch {
  Eigen::Vector2f outer_lo{-0.5f, -0.35f}, outer_hi{0.5f, 0.35f};
  Eigen::Vector2f hole_lo{-0.15f, -0.1f}, hole_hi{0.1f, 0.12f};
  PointCloud cloud;

  HoledPatch() {
    const float step = kPlanarVoxel / 6;
    for (float y = outer_lo.y(); y <= outer_hi.y() + 1e-6f; y += step)
      for (float x = outer_lo.x(); x <= outer_hi.x() + 1e-6f; x += step) {
        const bool in_hole =
            x > hole_lo.x() && x < hole_hi.x() && y > hole_lo.y() && y < hole_hi.y();
        if (in_hole) continue;
        cloud.positions.emplace_back(x, y, kHeight);
        cloud.normals.emplace_back(0.0f, 0.0f, 1.0f);
      }
  }
  float contour_distance(const Eigen::Vector3f& p) const {
    const Eigen::Vector2f q(p.x(), p.y());
    return std::min(to_rectangle_outline(q, outer_lo, outer_hi),
                    to_rectangle_outline(q, hole_lo, hole_hi));
  }
};

// Distances of the border vertices (on an edge used once) to the true contour, in voxels.
DistanceStats border_error(const TriangleMesh& mesh, const HoledPatch& patch) {
  std::vector<float> errors;
  std::vector<std::uint8_t> seen(mesh.vertices.size(), 0);
  for (const BorderEdge& e : border_edges(mesh))
    for (std::uint32_t v : {e.a, e.b})
      if (!seen[v]) {
        seen[v] = 1;
        errors.push_back(patch.contour_distance(mesh.vertices[v]) / kPlanarVoxel);
      }
  return distance_stats(errors);
}

TEST(PlanarMarchingCubes, MovesTheBorderOfAHoledRectangleOntoTheDataContour) {
  const HoledPatch patch;
  const KdTreeIndex index(patch.cloud.positions);
  const SparseGrid grid = voxelize(patch.cloud, VoxelizeConfig{kPlanarVoxel, 0.5f});
  const DistanceField field = hoppe_distance(grid, patch.cloud, index, DistanceConfig{});
  const TriangleMesh mc = marching_cubes(grid, field);
  const TriangleMesh pmc = planar_marching_cubes(grid, field, patch.cloud, index);
  const DistanceStats before = border_error(mc, patch), after = border_error(pmc, patch);
  std::printf(
      "[ pmc ] border to true contour: mc mean %.3f max %.3f voxel; pmc mean %.3f p95 %.3f "
      "max %.3f voxel (%zu border vertices)\n",
      before.mean, before.max, after.mean, after.p95, after.max, after.samples);
  EXPECT_EQ(mesh_topology(pmc).boundary_loops, 2u);  // the outline and the hole
  EXPECT_GT(before.mean, 0.3);
  EXPECT_LT(after.max, 0.2);
  // Heights are kept: every vertex stays on the plane.
  for (const auto& v : pmc.vertices) EXPECT_NEAR(v.z(), kHeight, 0.02f * kPlanarVoxel);
  EXPECT_LE(pmc.triangles.size(), mc.triangles.size());
  EXPECT_EQ(mesh_topology(pmc).edges.non_manifold_edges, 0u);
  EXPECT_EQ(mesh_topology(pmc).degenerate_faces, 0u);
}

TEST(PlanarMarchingCubes, SameOutputWithOneAndTwoThreads) {
  const HoledPatch patch;
  const KdTreeIndex index(patch.cloud.positions);
  const SparseGrid grid = voxelize(patch.cloud, VoxelizeConfig{kPlanarVoxel, 0.5f});
  const DistanceField field = hoppe_distance(grid, patch.cloud, index, DistanceConfig{});
  TriangleMesh one, two;
  {
    ThreadLimit limit(1);
    one = planar_marching_cubes(grid, field, patch.cloud, index);
  }
  {
    ThreadLimit limit(2);
    two = planar_marching_cubes(grid, field, patch.cloud, index);
  }
  EXPECT_GT(one.triangles.size(), 100u);
  EXPECT_EQ(one.vertices, two.vertices);
  EXPECT_EQ(one.triangles, two.triangles);
}

// Distance from p to the nearest of the 12 edges of the box centred at c with half sides h.
float to_box_edges(const Eigen::Vector3f& p, const Eigen::Vector3f& c, float h) {
  const Eigen::Vector3f q = (p - c).cwiseAbs() - Eigen::Vector3f::Constant(h);
  float best = std::numeric_limits<float>::infinity();
  for (int k = 0; k < 3; ++k) {  // the edges along axis k
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    const float along = std::max(q[k], 0.0f);
    best = std::min(best, std::sqrt(q[i] * q[i] + q[j] * q[j] + along * along));
  }
  return best;
}

// Planar marching cubes places no vertex on the box's edges (it cuts them off, as marching
// cubes does), but the data shows where they are: the vertices flagged there lie within about a
// voxel of a true edge (none farther: the faces' vertices are not flagged), and every true
// edge has flagged vertices all along it
// (the feature graph's seed, as extended marching cubes' feature vertices are).
TEST(PlanarMarchingCubes, FlagsTheVerticesAtTheBoxEdges) {
  const auto s = test::sampled_solid(test::test_solids(kPlanarVoxel)[0].solid, kPlanarVoxel);
  const Eigen::Vector3f c(0.013f, -0.021f, 0.007f);
  constexpr float kHalf = 0.4f;
  const TriangleMesh mesh = planar_marching_cubes(s.grid, s.field, s.solid.samples, *s.index);
  const std::vector<std::uint8_t> flags =
      data_feature_vertices(mesh, s.solid.samples, *s.index, kPlanarVoxel);
  ASSERT_EQ(flags.size(), mesh.vertices.size());
  std::size_t flagged = 0;
  float farthest = 0.0f;
  for (std::size_t v = 0; v < flags.size(); ++v)
    if (flags[v]) {
      ++flagged;
      farthest = std::max(farthest, to_box_edges(mesh.vertices[v], c, kHalf) / kPlanarVoxel);
    }
  // Coverage: points along every edge, each with a flagged vertex within 1.5 voxels.
  std::size_t samples = 0, covered = 0;
  for (int corner = 0; corner < 8; ++corner)
    for (int axis = 0; axis < 3; ++axis) {
      const Eigen::Vector3f sign(corner & 1 ? 1.f : -1.f, corner & 2 ? 1.f : -1.f,
                                 corner & 4 ? 1.f : -1.f);
      if (sign[axis] > 0) continue;  // each edge once, from its lower end
      for (float t = 0.0f; t <= 2.0f * kHalf; t += 0.25f * kPlanarVoxel) {
        Eigen::Vector3f p = c + kHalf * sign;
        p[axis] += t;
        ++samples;
        for (std::size_t v = 0; v < flags.size(); ++v)
          if (flags[v] && (mesh.vertices[v] - p).norm() <= 1.5f * kPlanarVoxel) {
            ++covered;
            break;
          }
      }
    }
  std::printf(
      "[ pmc ] box: %zu of %zu vertices flagged, farthest %.2f voxels from an edge, "
      "%zu of %zu points along the edges within 1.5 voxels of one\n",
      flagged, mesh.vertices.size(), static_cast<double>(farthest), covered, samples);
  EXPECT_GT(flagged, 0u);
  EXPECT_LT(farthest, 1.5f);
  EXPECT_EQ(covered, samples);
  PointCloud no_normals = s.solid.samples;
  no_normals.normals.clear();
  const auto none = data_feature_vertices(mesh, no_normals, *s.index, kPlanarVoxel);
  EXPECT_EQ(std::count(none.begin(), none.end(), 1), 0);
}

}  // namespace
}  // namespace meshflow
