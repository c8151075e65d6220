#include "nodes/extract/marching_tetrahedra.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "fixtures/solid_fixture.h"
#include "nodes/synthetic/shapes.h"
#include "runtime/threads.h"

namespace meshflow {
namespace {

constexpr float kTetraVoxel = 0.05f;

TEST(MarchingTetrahedra, ClosedOrientedAndNearTheSurfaceOnEveryShape) {
  for (const auto& named : test::test_solids(kTetraVoxel)) {
    SCOPED_TRACE(named.name);
    const auto s = test::sampled_solid(named.solid, kTetraVoxel);
    const TriangleMesh mt = marching_tetrahedra(s.grid, s.field);
    const TriangleMesh mc = marching_cubes(s.grid, s.field);
    ASSERT_GT(mt.triangles.size(), 100u);
    const EdgeStatistics stats = edge_statistics(mt);
    EXPECT_TRUE(stats.closed()) << stats.boundary_edges << " boundary, " << stats.non_manifold_edges
                                << " non-manifold edges";
    EXPECT_EQ(stats.inconsistent_edges, 0u);
    // Outward: the signed volume is positive and close to marching cubes' volume.
    auto volume = [](const TriangleMesh& m) {
      double v = 0.0;
      for (const Triangle& t : m.triangles)
        v += m.vertices[t[0]].cast<double>().dot(
                 m.vertices[t[1]].cast<double>().cross(m.vertices[t[2]].cast<double>())) /
             6.0;
      return v;
    };
    EXPECT_GT(volume(mt), 0.0);
    EXPECT_NEAR(volume(mt), volume(mc), 0.02 * volume(mc));
    double mean = 0.0;
    for (const auto& v : mt.vertices) mean += std::abs(s.solid.sdf(v));
    mean /= static_cast<double>(mt.vertices.size());
    std::printf("[ mt ] %s: %zu triangles (mc %zu, %.2fx), mean |sdf| %.4f voxel\n",
                named.name.c_str(), mt.triangles.size(), mc.triangles.size(),
                static_cast<double>(mt.triangles.size()) / static_cast<double>(mc.triangles.size()),
                mean / kTetraVoxel);
    EXPECT_LT(mean, 0.2 * kTetraVoxel);
  }
}

TEST(MarchingTetrahedra, SphereFieldHasSharedVerticesAndNoDegenerateTriangles) {
  const auto s = test::sampled_solid(
      synthetic::Solid{
          [](const Eigen::Vector3f& p) { return p.norm() - 0.5f; },
          make_solid(synthetic::Cylinder{{0, 0, 0}, 0.3f, 0.2f}, kTetraVoxel / 4).samples},
      kTetraVoxel);
  const TriangleMesh mesh = marching_tetrahedra(s.grid, s.field);
  ASSERT_FALSE(mesh.empty());
  // Shared vertices: no two vertices at the same position.
  std::vector<std::array<float, 3>> keys;
  for (const auto& v : mesh.vertices) keys.push_back({v.x(), v.y(), v.z()});
  std::sort(keys.begin(), keys.end());
  EXPECT_EQ(std::adjacent_find(keys.begin(), keys.end()), keys.end());
  for (const Triangle& t : mesh.triangles) {
    EXPECT_TRUE(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
    EXPECT_GT(face_normal(mesh, t).norm(), 0.5f);
  }
}

TEST(MarchingTetrahedra, SameOutputWithOneAndTwoThreads) {
  const auto s = test::sampled_solid(test::test_solids(kTetraVoxel)[2].solid, kTetraVoxel);
  TriangleMesh one, two;
  {
    ThreadLimit limit(1);
    one = marching_tetrahedra(s.grid, s.field);
  }
  {
    ThreadLimit limit(2);
    two = marching_tetrahedra(s.grid, s.field);
  }
  EXPECT_GT(one.triangles.size(), 100u);
  EXPECT_EQ(one.vertices, two.vertices);
  EXPECT_EQ(one.triangles, two.triangles);
}

}  // namespace
}  // namespace meshflow
