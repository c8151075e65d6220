// mesh_statistics() against analytic ground truth: a box (exact area and volume), a
// parametric torus (genus 1), a subdivided sphere, an open grid and broken meshes.

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "nodes/eval/mesh_statistics.h"
#include "test_support.h"

namespace meshflow {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The axis-aligned box [0, a] x [0, b] x [0, c]: 8 vertices, 12 triangles facing outward.
TriangleMesh box_mesh(float a, float b, float c) {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back(i & 1 ? a : 0.0f, i & 2 ? b : 0.0f, i & 4 ? c : 0.0f);
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

// The torus of radii R (centre line) and r (tube) about z, n x m quads split in two,
// counter-clockwise seen from outside.
TriangleMesh torus_mesh(float R, float r, int n, int m) {
  TriangleMesh t;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const double u = 2 * kPi * i / n, v = 2 * kPi * j / m;
      t.vertices.emplace_back(static_cast<float>((R + r * std::cos(v)) * std::cos(u)),
                              static_cast<float>((R + r * std::cos(v)) * std::sin(u)),
                              static_cast<float>(r * std::sin(v)));
    }
  const auto id = [&](int i, int j) { return static_cast<std::uint32_t>((i % n) * m + (j % m)); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      t.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      t.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return t;
}

// The unit sphere: an octahedron subdivided `levels` times, vertices pushed onto the sphere.
TriangleMesh sphere_mesh(int levels) {
  TriangleMesh s;
  s.vertices = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  s.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                 {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (int level = 0; level < levels; ++level) {
    std::map<std::uint64_t, std::uint32_t> middle;
    const auto mid = [&](std::uint32_t a, std::uint32_t b) {
      const auto [it, added] = middle.emplace(undirected_edge_key(a, b), 0u);
      if (added) {
        it->second = static_cast<std::uint32_t>(s.vertices.size());
        const Eigen::Vector3f p = (s.vertices[a] + s.vertices[b]).normalized();
        s.vertices.push_back(p);
      }
      return it->second;
    };
    std::vector<Triangle> finer;
    for (const Triangle& t : s.triangles) {
      const std::uint32_t ab = mid(t[0], t[1]), bc = mid(t[1], t[2]), ca = mid(t[2], t[0]);
      finer.insert(finer.end(), {{t[0], ab, ca}, {ab, t[1], bc}, {ca, bc, t[2]}, {ab, bc, ca}});
    }
    s.triangles = std::move(finer);
  }
  return s;
}

TEST(MeshStatistics, BoxHasItsExactAreaAndVolume) {
  const MeshStatistics s = mesh_statistics(box_mesh(0.8f, 0.6f, 0.5f));
  EXPECT_EQ(s.vertices, 8u);
  EXPECT_EQ(s.triangles, 12u);
  EXPECT_NEAR(s.area, 2 * (0.8 * 0.6 + 0.8 * 0.5 + 0.6 * 0.5), 1e-6);
  ASSERT_TRUE(s.closed);
  ASSERT_TRUE(s.volume.has_value());
  EXPECT_NEAR(*s.volume, 0.8 * 0.6 * 0.5, 1e-6);
  EXPECT_EQ(s.euler_characteristic, 2);
  ASSERT_TRUE(s.genus.has_value());
  EXPECT_EQ(*s.genus, 0);
  EXPECT_EQ(s.components, 1u);
  EXPECT_EQ(s.topology.boundary_loops, 0u);
  EXPECT_EQ(s.non_manifold_vertices, 0u);
  EXPECT_TRUE(s.bounds.min().isZero());
  EXPECT_TRUE(s.bounds.max().isApprox(Eigen::Vector3f(0.8f, 0.6f, 0.5f)));
}

TEST(MeshStatistics, InsideOutBoxHasANegativeVolume) {
  TriangleMesh box = box_mesh(1, 1, 1);
  for (Triangle& t : box.triangles) std::swap(t[1], t[2]);
  const MeshStatistics s = mesh_statistics(box);
  ASSERT_TRUE(s.volume.has_value());
  EXPECT_NEAR(*s.volume, -1.0, 1e-6);
}

TEST(MeshStatistics, TorusHasGenusOne) {
  const float R = 0.4f, r = 0.15f;
  const MeshStatistics s = mesh_statistics(torus_mesh(R, r, 256, 128));
  EXPECT_EQ(s.euler_characteristic, 0);
  ASSERT_TRUE(s.genus.has_value());
  EXPECT_EQ(*s.genus, 1);
  EXPECT_EQ(s.components, 1u);
  EXPECT_EQ(s.topology.boundary_loops, 0u);
  EXPECT_NEAR(s.area, 4 * kPi * kPi * R * r, 0.002 * 4 * kPi * kPi * R * r);
  ASSERT_TRUE(s.volume.has_value());
  EXPECT_NEAR(*s.volume, 2 * kPi * kPi * R * r * r, 0.003 * 2 * kPi * kPi * R * r * r);
}

TEST(MeshStatistics, SubdividedSphereApproachesTheUnitSphere) {
  const MeshStatistics s = mesh_statistics(sphere_mesh(6));
  EXPECT_NEAR(s.area, 4 * kPi, 0.002 * 4 * kPi);
  ASSERT_TRUE(s.volume.has_value());
  EXPECT_NEAR(*s.volume, 4.0 / 3.0 * kPi, 0.003 * 4.0 / 3.0 * kPi);
  ASSERT_TRUE(s.genus.has_value());
  EXPECT_EQ(*s.genus, 0);
  EXPECT_EQ(s.euler_characteristic, 2);
  EXPECT_NEAR(s.bounds.min().x(), -1.0f, 1e-6f);
}

TEST(MeshStatistics, OpenGridHasOneBorderLoopAndNoVolume) {
  const MeshStatistics s = mesh_statistics(test::grid_mesh(5));
  EXPECT_NEAR(s.area, 16.0, 1e-9);
  EXPECT_FALSE(s.closed);
  EXPECT_FALSE(s.volume.has_value());
  EXPECT_EQ(s.topology.boundary_loops, 1u);
  EXPECT_EQ(s.topology.edges.boundary_edges, 16u);
  EXPECT_EQ(s.euler_characteristic, 1);  // a disc
  ASSERT_TRUE(s.genus.has_value());
  EXPECT_EQ(*s.genus, 0);
}

TEST(MeshStatistics, CountsComponentsUnusedVerticesAndNonManifoldVertices) {
  // Two boxes apart, and an unused vertex: two components, genus 0 in all.
  TriangleMesh two = box_mesh(1, 1, 1);
  const TriangleMesh other = box_mesh(1, 1, 1);
  for (const Triangle& t : other.triangles) two.triangles.push_back({t[0] + 8, t[1] + 8, t[2] + 8});
  for (const Eigen::Vector3f& v : other.vertices)
    two.vertices.push_back(v + Eigen::Vector3f(3, 0, 0));
  two.vertices.emplace_back(100, 100, 100);
  MeshStatistics s = mesh_statistics(two);
  EXPECT_EQ(s.components, 2u);
  EXPECT_EQ(s.vertices, 17u);
  EXPECT_EQ(s.referenced_vertices, 16u);
  EXPECT_EQ(s.euler_characteristic, 4);
  ASSERT_TRUE(s.genus.has_value());
  EXPECT_EQ(*s.genus, 0);
  EXPECT_NEAR(*s.volume, 2.0, 1e-6);
  EXPECT_NEAR(s.bounds.max().x(), 4.0f, 1e-6f);  // the unused vertex is outside the bounds

  // Two tetrahedra touching at one vertex: one component, a non-manifold vertex, no genus.
  TriangleMesh touching = test::tetrahedron();
  for (const Triangle& t : test::tetrahedron().triangles) {
    Triangle u = t;
    for (std::uint32_t& v : u) v = v == 0 ? 0 : v + 3;  // shares vertex 0
    touching.triangles.push_back(u);
  }
  for (int i = 1; i < 4; ++i) touching.vertices.push_back(-test::tetrahedron().vertices[i]);
  s = mesh_statistics(touching);
  EXPECT_EQ(s.components, 1u);
  EXPECT_EQ(s.non_manifold_vertices, 1u);
  EXPECT_EQ(s.topology.edges.non_manifold_edges, 0u);
  EXPECT_FALSE(s.genus.has_value());

  // A degenerate triangle and a third face on an edge.
  TriangleMesh broken = test::tetrahedron();
  broken.triangles.push_back({0, 0, 1});
  broken.triangles.push_back({0, 1, 2});
  s = mesh_statistics(broken);
  EXPECT_EQ(s.topology.degenerate_faces, 1u);
  EXPECT_GT(s.topology.edges.non_manifold_edges, 0u);
  EXPECT_FALSE(s.closed);
  EXPECT_FALSE(s.genus.has_value());
}

}  // namespace
}  // namespace meshflow
