#include "nodes/optimize/planar/planar_regions.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>

#include "fixtures/mesh_fixtures.h"
#include "fixtures/room_fixture.h"
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

// A height field z = f(x, y) on an n x n grid with 1 cm spacing.
TriangleMesh sampled_height_field(std::uint32_t n, const std::function<float(float, float)>& f) {
  TriangleMesh m = test::grid_mesh(n);
  for (Eigen::Vector3f& v : m.vertices) {
    v.x() *= 0.01f;
    v.y() *= 0.01f;
    v.z() = f(v.x(), v.y());
  }
  return m;
}

TEST(PlanarRegions, ACurvedSurfaceIsNotTakenForAPlane) {
  // A cylinder of radius 0.3 m seen from above over 0.4 m: its normals stay within 42 degrees,
  // so it grows regions, but no plane explains them within 2 mm.
  const TriangleMesh bowl = sampled_height_field(
      41, [](float x, float) { return std::sqrt(0.09f - (x - 0.2f) * (x - 0.2f)); });
  PlanarRegionConfig config;
  EXPECT_FALSE(grow_planar_regions(HalfEdgeMesh(bowl), config).regions.empty())
      << "without the check the curved surface is segmented into planes";
  config.max_deviation = 0.002f;
  HalfEdgeMesh h(bowl);
  const PlanarSegmentation s = grow_planar_regions(h, config);
  for (const PlanarRegion& r : s.regions) EXPECT_LE(r.deviation, config.max_deviation);
  const std::vector<Eigen::Vector3f> before = bowl.vertices;
  project_onto_planes(h, s);
  for (std::uint32_t v = 0; v < before.size(); ++v)
    EXPECT_LE((h.position(v) - before[v]).norm(), config.max_deviation * 1.001f);
}

TEST(PlanarRegions, StraySpotsDoNotTiltAnExactPlane) {
  // An exact plane z = 0 (an extraction without noise: roughness 0) with 24 vertices lifted
  // 1.5 mm, within the 2 mm tolerance: a plane through every vertex would sit 2e-5 m above the
  // exact one and the projection would lift the whole sheet by that; the trimmed fit finds the
  // exact plane and only the stray vertices move.
  TriangleMesh sheet = sampled_height_field(41, [](float, float) { return 0.0f; });
  for (std::uint32_t k = 0; k < 24; ++k)
    sheet.vertices[(41 * (1 + k) + 3 + 7 * k % 30)].z() = 0.0015f;
  PlanarRegionConfig config;
  config.max_deviation = 0.002f;
  HalfEdgeMesh h(sheet);
  const PlanarSegmentation s = grow_planar_regions(h, config);
  ASSERT_EQ(s.regions.size(), 1u);
  EXPECT_NEAR(s.regions[0].normal.z(), 1.0f, 1e-7f);
  EXPECT_NEAR(s.regions[0].offset, 0.0f, 1e-7f);
  EXPECT_LT(s.tolerance, 1e-5f) << "a smooth mesh is held to a tighter tolerance";
  project_onto_planes(h, s);
  for (std::uint32_t v = 0; v < sheet.vertices.size(); ++v)
    EXPECT_NEAR(h.position(v).z(), 0.0f, 1e-7f) << "vertex " << v;
}

TEST(PlanarRegions, AClutteredWallKeepsTheWallAndLeavesTheClutter) {
  // A flat 0.6 m square with a smooth 2 cm bump (something on the wall, slopes within 15
  // degrees, so the whole square grows as one region): the region shrinks to the flat part and
  // the bump keeps its shape. The mesh is exact, so the region is held to the tight tolerance
  // of a smooth mesh: the bump's skirt down to a few micrometres stays out (about a quarter of
  // the square), where 2 mm would flatten it by up to 2 mm.
  const TriangleMesh wall = sampled_height_field(61, [](float x, float y) {
    const float r2 = (x - 0.45f) * (x - 0.45f) + (y - 0.45f) * (y - 0.45f);
    return 0.02f * std::exp(-r2 / (2.0f * 0.04f * 0.04f));
  });
  PlanarRegionConfig config;
  ASSERT_EQ(grow_planar_regions(HalfEdgeMesh(wall), config).regions.size(), 1u);
  config.max_deviation = 0.002f;
  HalfEdgeMesh h(wall);
  const PlanarSegmentation s = grow_planar_regions(h, config);
  ASSERT_EQ(s.regions.size(), 1u);
  EXPECT_GT(s.regions[0].faces.size(), wall.triangles.size() * 2 / 3);
  EXPECT_LT(s.regions[0].faces.size(), wall.triangles.size());
  for (std::uint32_t f : s.regions[0].faces)
    for (int k = 0; k < 3; ++k) EXPECT_LT(wall.vertices[wall.triangles[f][k]].z(), 0.0025f);
  project_onto_planes(h, s);
  const std::uint32_t peak = 45 * 61 + 45;
  EXPECT_NEAR(h.position(peak).z(), 0.02f, 1e-6f) << "the bump was flattened";
}

}  // namespace
}  // namespace meshflow
