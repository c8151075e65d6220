#include "nodes/close/close_surface.h"

#include <gtest/gtest.h>

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

TEST(CloseSurface, KeepsObservedDistancesAndGivesAWatertightSurface) {
  const float voxel = 0.02f;
  const CappedSphere s = capped_sphere(voxel);
  const TriangleMesh open = marching_cubes(s.grid, s.field);
  ASSERT_GT(edge_statistics(open).boundary_edges, 0u) << "the cap is open before closing";
  CloseReport report;
  const ClosedDistance closed = close_distance_field(s.grid, s.field, s.cloud, {}, &report);
  EXPECT_TRUE(report.ran);
  EXPECT_GT(report.filled, 0u);
  EXPECT_GT(report.cells_added, 0u);
  EXPECT_EQ(report.seen_empty, 0u) << "no sensor";
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

TEST(CloseSurface, LinesOfSightStayEmpty) {
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
  const ClosedDistance closed = close_distance_field(s.grid, s.field, rays, {}, &report);
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

TEST(CloseSurface, SameResultForOneAndTwoThreads) {
  const CappedSphere s = capped_sphere(0.025f);
  const auto run = [&] { return close_distance_field(s.grid, s.field, s.cloud); };
  const ClosedDistance one = test::with_threads(1, run), two = test::with_threads(2, run);
  EXPECT_EQ(one.grid.cells, two.grid.cells);
  EXPECT_EQ(one.distance.values, two.distance.values);
}

TEST(CloseSurface, RefusesALatticeOverTheLimit) {
  const CappedSphere s = capped_sphere(0.02f);
  CloseConfig config;
  config.max_lattice_corners = 1000;
  EXPECT_THROW(close_distance_field(s.grid, s.field, s.cloud, config), Error);
}

}  // namespace
}  // namespace meshflow
