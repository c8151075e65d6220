#include "nodes/close/close_surface.h"

#include <gtest/gtest.h>

#include <cstdio>

#include "nodes/extract/marching_cubes.h"
#include "nodes/synthetic/closed_objects.h"
#include "nodes/voxelize/voxelize.h"
#include "runtime/error.h"
#include "runtime/triangle_mesh.h"
#include "test_support.h"

namespace meshflow {
namespace {

// A sphere's points without its top cap (z > 0.3 m unseen), the grid around them and the exact
// signed distance at corners within 2 voxels of a point.
struct CappedSphere {
  PointCloud cloud;
  SparseGrid grid;
  DistanceField field;
};

CappedSphere capped_sphere(float voxel) {
  CappedSphere s;
  const PointCloud all = synthetic::sphere_object().sample(30000, 0.0f, 5);
  std::vector<std::uint32_t> keep;
  for (std::uint32_t i = 0; i < all.size(); ++i)
    if (all.positions[i].z() < 0.3f) keep.push_back(i);
  s.cloud = select_points(all, keep);
  s.grid = voxelize(s.cloud, VoxelizeConfig{voxel});
  s.field.values.resize(s.grid.corners.size());
  s.field.valid.resize(s.grid.corners.size());
  for (std::size_t c = 0; c < s.grid.corners.size(); ++c) {
    const Eigen::Vector3f q = s.grid.corner_position(c);
    s.field.values[c] = q.norm() - 0.5f;
    // Corners near the missing cap have no data.
    s.field.valid[c] = q.z() < 0.3f + voxel ? 1 : 0;
  }
  return s;
}

// A lattice small enough to solve at once, and the same forced into a coarse lattice (every
// 4th corner) and tiles of 16 cells: both keep the data, close the cap near the sphere.
CloseConfig tiled_config() {
  CloseConfig config;
  config.max_dense_corners = 20000;
  config.tile_cells = 16;
  return config;
}

class CloseSurfaceModes : public ::testing::TestWithParam<bool> {};

TEST_P(CloseSurfaceModes, KeepsObservedDistancesAndGivesAWatertightSurface) {
  const bool tiled = GetParam();
  const float voxel = 0.02f;
  const CappedSphere s = capped_sphere(voxel);
  const TriangleMesh open = marching_cubes(s.grid, s.field);
  ASSERT_GT(edge_statistics(open).boundary_edges, 0u) << "the cap is open before closing";
  CloseReport report;
  const ClosedDistance closed = close_distance_field(
      s.grid, s.field, s.cloud, tiled ? tiled_config() : CloseConfig{}, &report);
  EXPECT_TRUE(report.ran);
  EXPECT_GT(report.filled, 0u);
  EXPECT_GT(report.cells_added, 0u);
  EXPECT_EQ(report.seen_empty, 0u) << "no sensor";
  EXPECT_EQ(report.observed, s.field.valid_count()) << "each data corner counted once";
  if (tiled) {
    EXPECT_GE(report.coarse_step, 2);
    EXPECT_GT(report.tiles, 8u);
    // 60 x 60 x 60 corners in tiles of 16 cells: 4 x 4 x 4, the corner tiles outside skipped.
    EXPECT_LT(report.tiles, 64u);
  } else {
    EXPECT_EQ(report.coarse_step, 1);
    EXPECT_EQ(report.tiles, 1u);
  }
  // Every corner with data keeps its value exactly.
  for (std::size_t c = 0; c < s.grid.corners.size(); ++c) {
    if (!s.field.valid[c]) continue;
    const std::uint32_t at = closed.grid.find_corner(unpack_key(s.grid.corners[c]));
    ASSERT_NE(at, UINT32_MAX);
    ASSERT_EQ(closed.distance.values[at], s.field.values[c]);
  }
  const TriangleMesh mesh = marching_cubes(closed.grid, closed.distance);
  const EdgeStatistics stats = edge_statistics(mesh);
  EXPECT_TRUE(stats.closed()) << stats.boundary_edges << " border, " << stats.non_manifold_edges
                              << " non-manifold edges";
  // The fill spans the cap's opening (a disc of radius 0.4 m at z = 0.3) and stays within the
  // sphere's cap height of it.
  float top = -1.0f;
  for (const Eigen::Vector3f& v : mesh.vertices) top = std::max(top, v.z());
  EXPECT_GT(top, 0.3f);
  EXPECT_LT(top, 0.5f + voxel);
}

TEST_P(CloseSurfaceModes, LinesOfSightStayEmpty) {
  // The capped sphere seen from above through its opening: the sensor's rays to the inner
  // bottom cross the missing cap, so nothing may close it; the inside stays open to the sensor.
  const float voxel = 0.02f;
  CappedSphere s = capped_sphere(voxel);
  // Only the inner surface of the bowl is seen: flip to a bowl seen from inside.
  s.cloud.sensor_origin = Eigen::Vector3f(0.0f, 0.0f, 1.5f);
  s.cloud.has_sensor_origin = true;
  std::vector<std::uint32_t> seen;
  for (std::uint32_t i = 0; i < s.cloud.size(); ++i)
    if (s.cloud.positions[i].z() < -0.1f) seen.push_back(i);  // the bottom, visible inside
  const PointCloud rays = select_points(s.cloud, seen);
  CloseReport report;
  const ClosedDistance closed = close_distance_field(
      s.grid, s.field, rays, GetParam() ? tiled_config() : CloseConfig{}, &report);
  EXPECT_GT(report.seen_empty, 0u);
  for (std::size_t c = 0; c < closed.grid.corners.size(); ++c) {
    const Eigen::Vector3f q = closed.grid.corner_position(c);
    // On the axis, between the opening and 2 voxels above the bottom: seen empty.
    if (q.head<2>().norm() < 0.5f * voxel && q.z() > -0.5f + 3.0f * voxel && q.z() < 0.45f) {
      ASSERT_GT(closed.distance.values[c], 0.0f) << q.transpose();
    }
  }
  const TriangleMesh mesh = marching_cubes(closed.grid, closed.distance);
  for (const Eigen::Vector3f& v : mesh.vertices)
    EXPECT_FALSE(v.head<2>().norm() < 0.1f && v.z() > 0.2f && v.z() < 0.45f)
        << "a fill across the seen opening at " << v.transpose();
}

INSTANTIATE_TEST_SUITE_P(DenseAndTiled, CloseSurfaceModes, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& p) {
                           return p.param ? "Tiled" : "Dense";
                         });

// An unseen box bottom closes flat at its rim: the box (0.8 x 0.6 x 0.5 m) seen on its sides
// and top only, with the exact signed distance at the grid's corners away from the bottom.
// Diffusing the distance between the band's few held values domed the bottom deep into the
// box (the harmonic fill of a cavity takes the value of its nearest held wall); the double
// layer spans the planar rim with the plane, the gradient fill closes it where the walls' and
// the top's fields meet near the lattice's face.
TEST(CloseSurface, UnseenBoxBottomClosesFlatAtItsRim) {
  const float voxel = 0.02f;
  const Eigen::Vector3f half(0.4f, 0.3f, 0.25f);
  PointCloud cloud;
  const float spacing = 0.5f * voxel;
  for (float u = -1.0f; u <= 1.0f; u += spacing / 0.4f)
    for (float v = -1.0f; v <= 1.0f; v += spacing / 0.4f) {
      cloud.positions.emplace_back(u * half.x(), v * half.y(), half.z());  // top
      for (const float side : {-1.0f, 1.0f}) {
        const float z = 0.5f * (v + 1.0f) * 2.0f * half.z() - half.z();
        cloud.positions.emplace_back(side * half.x(), u * half.y(), z);
        cloud.positions.emplace_back(u * half.x(), side * half.y(), z);
      }
    }
  const SparseGrid grid = voxelize(cloud, VoxelizeConfig{voxel});
  DistanceField field;
  field.values.resize(grid.corners.size());
  field.valid.resize(grid.corners.size());
  for (std::size_t c = 0; c < grid.corners.size(); ++c) {
    const Eigen::Vector3f q = grid.corner_position(c);
    const Eigen::Vector3f d = q.cwiseAbs() - half;
    field.values[c] = d.cwiseMax(0.0f).norm() + std::min(d.maxCoeff(), 0.0f);
    field.valid[c] = q.z() > -half.z() + voxel ? 1 : 0;  // the bottom unseen
  }
  for (const CloseFill fill : {CloseFill::indicator, CloseFill::gradient}) {
    SCOPED_TRACE(close_fill_name(fill));
    CloseConfig config;
    config.fill = fill;
    const ClosedDistance closed = close_distance_field(grid, field, cloud, config);
    const TriangleMesh mesh = marching_cubes(closed.grid, closed.distance);
    ASSERT_TRUE(edge_statistics(mesh).closed());
    double sum = 0.0, worst = 0.0;
    std::size_t bottom = 0;
    for (const Eigen::Vector3f& v : mesh.vertices) {
      // The bottom's inner part, seen from below (away from the walls' bands).
      if (std::abs(v.x()) > half.x() - 3.0f * voxel || std::abs(v.y()) > half.y() - 3.0f * voxel ||
          v.z() > 0.0f)
        continue;
      const double error = std::abs(static_cast<double>(v.z()) + half.z());
      sum += error;
      worst = std::max(worst, error);
      ++bottom;
    }
    ASSERT_GT(bottom, 100u);
    std::printf("[ bottom ] %s: %zu vertices: mean %.4f, largest %.4f m from the box's bottom\n",
                close_fill_name(fill), bottom, sum / static_cast<double>(bottom), worst);
    EXPECT_LT(sum / static_cast<double>(bottom), 2.0 * voxel) << "mean distance to the bottom";
    EXPECT_LT(worst, 3.0 * voxel) << "largest distance to the bottom";
  }
}

TEST(CloseSurface, SameResultForOneAndTwoThreads) {
  const CappedSphere s = capped_sphere(0.025f);
  for (const CloseConfig& config : {CloseConfig{}, tiled_config()}) {
    const auto run = [&] { return close_distance_field(s.grid, s.field, s.cloud, config); };
    const ClosedDistance one = test::with_threads(1, run), two = test::with_threads(2, run);
    EXPECT_EQ(one.grid.cells, two.grid.cells);
    EXPECT_EQ(one.distance.values, two.distance.values);
  }
}

// The tiled solve follows the dense diffusion: the filled cap's corners differ by little (its
// tile faces hold the coarse solution of every 4th corner).
TEST(CloseSurface, TiledFillFollowsTheDenseOne) {
  const float voxel = 0.02f;
  const CappedSphere s = capped_sphere(voxel);
  CloseConfig diffusion;  // the tiles' fill
  diffusion.fill = CloseFill::diffusion;
  const ClosedDistance dense = close_distance_field(s.grid, s.field, s.cloud, diffusion);
  const ClosedDistance tiled = close_distance_field(s.grid, s.field, s.cloud, tiled_config());
  double worst = 0.0, sum = 0.0;
  std::size_t compared = 0;
  for (std::size_t c = 0; c < dense.grid.corners.size(); ++c) {
    const std::uint32_t at = tiled.grid.find_corner(unpack_key(dense.grid.corners[c]));
    if (at == UINT32_MAX) continue;
    const double d = std::abs(dense.distance.values[c] - tiled.distance.values[at]);
    worst = std::max(worst, d);
    sum += d;
    ++compared;
  }
  ASSERT_GT(compared, dense.grid.corners.size() / 2);
  std::printf("[ tiled ] corners both grids have: mean difference %.4f, largest %.4f m\n",
              sum / static_cast<double>(compared), worst);
  EXPECT_LT(sum / static_cast<double>(compared), 0.1 * voxel) << "mean difference";
  EXPECT_LT(worst, 2.0 * voxel) << "largest difference at a corner both grids have";
}

}  // namespace
}  // namespace meshflow
