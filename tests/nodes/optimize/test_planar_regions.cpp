#include "nodes/optimize/planar_regions.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "mesh_fixtures.h"
#include "room_fixture.h"
#include "test_support.h"

namespace meshflow {
namespace {

constexpr float kRegionVoxel = test::kRoomVoxel;
using test::room_mesh;

TEST(PlanarRegions, RoomSegmentsIntoClassifiedPlanesAndProjectsOntoThem) {
  const TriangleMesh& mesh = room_mesh();
  ASSERT_GT(mesh.triangles.size(), 10000u);
  HalfEdgeMesh h(mesh);
  const PlanarSegmentation s = grow_planar_regions(h);
  std::size_t floors = 0, ceilings = 0, walls = 0, assigned = 0;
  for (const PlanarRegion& r : s.regions) {
    floors += r.kind == RegionClass::kFloor ? 1 : 0;
    ceilings += r.kind == RegionClass::kCeiling ? 1 : 0;
    walls += r.kind == RegionClass::kWall ? 1 : 0;
    assigned += r.faces.size();
  }
  std::printf(
      "[ planes ] %zu triangles -> %zu regions (%zu floor/top, %zu ceiling, %zu wall), "
      "%.1f%% of faces assigned\n",
      mesh.triangles.size(), s.regions.size(), floors, ceilings, walls,
      100.0 * static_cast<double>(assigned) / static_cast<double>(mesh.triangles.size()));
  EXPECT_GE(s.regions.size(), 6u);
  EXPECT_LE(s.regions.size(), 80u);  // a few dozen
  EXPECT_GE(floors, 2u);             // the floor and the table / cabinet tops
  EXPECT_GE(ceilings, 1u);
  EXPECT_GE(walls, 4u);
  // The largest region facing up is the floor, z = 0.
  const PlanarRegion* floor = nullptr;
  for (const PlanarRegion& r : s.regions)
    if (r.kind == RegionClass::kFloor && (!floor || r.faces.size() > floor->faces.size()))
      floor = &r;
  ASSERT_NE(floor, nullptr);
  EXPECT_GT(floor->normal.z(), 0.999f);
  EXPECT_NEAR(floor->offset, 0.0f, 0.1f * kRegionVoxel);
  // After projection, the floor's interior vertices lie on the true floor within 0.1 voxel.
  const std::size_t moved = project_onto_planes(h, s);
  EXPECT_GT(moved, 1000u);
  std::size_t on_floor = 0;
  for (std::uint32_t f : floor->faces)
    for (std::uint32_t k = 0; k < 3; ++k) {
      const std::uint32_t v = h.from(3 * f + k);
      bool interior = true;
      for (std::uint32_t e : h.ring(v))
        interior = interior && s.region_of_face[HalfEdgeMesh::face(e)] == s.region_of_face[f];
      if (!interior) continue;
      EXPECT_NEAR(h.position(v).z(), 0.0f, 0.1f * kRegionVoxel);
      ++on_floor;
    }
  EXPECT_GT(on_floor, 1000u);
  EXPECT_EQ(h.check(), "");
}

TEST(PlanarRegions, ABentSheetSplitsAtTheBendAndSmallRegionsAreDropped) {
  const TriangleMesh m = test::bent_sheet();
  HalfEdgeMesh h(m);
  const PlanarSegmentation s = grow_planar_regions(h);
  ASSERT_EQ(s.regions.size(), 2u);
  EXPECT_EQ(s.regions[0].kind, RegionClass::kFloor);  // z = 0, facing up
  EXPECT_NEAR(s.regions[1].normal.dot(Eigen::Vector3f(-1, 0, 1).normalized()), 1.0f, 1e-4f);
  for (std::int32_t r : s.region_of_face) EXPECT_GE(r, 0);
  PlanarRegionConfig big;
  big.min_region_faces = 1000;
  EXPECT_TRUE(grow_planar_regions(h, big).regions.empty());
}

TEST(PlanarRegions, ProjectionLeavesVerticesBeyondTheLimitWhereTheyAre) {
  // A flat 10 x 10 sheet with one interior vertex lifted 0.4 (its faces tilt by less than the
  // normal threshold, so they stay in the sheet's region).
  TriangleMesh m = test::grid_mesh(10);
  const std::uint32_t lifted = 5 * 10 + 5;
  m.vertices[lifted].z() = 0.4f;
  for (const float limit : {0.0f, 0.2f}) {
    HalfEdgeMesh h(m);
    const PlanarSegmentation s = grow_planar_regions(h, PlanarRegionConfig{0.85f, 10});
    ASSERT_EQ(s.regions.size(), 1u);
    const std::size_t moved = project_onto_planes(h, s, limit);
    const float offset = std::abs(h.position(lifted).z() - m.vertices[lifted].z());
    if (limit == 0.0f) {
      EXPECT_GT(offset, 0.3f);  // flattened with the rest
    } else {
      EXPECT_EQ(offset, 0.0f);  // 0.4 from the plane: left alone
      EXPECT_GT(moved, 0u);     // the interior vertices near the plane still moved
    }
  }
}

}  // namespace
}  // namespace meshflow
