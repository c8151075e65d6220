#include "runtime/triangle_mesh.h"

#include <gtest/gtest.h>

namespace meshflow {
namespace {

TriangleMesh tetrahedron() {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};  // outward, counter-clockwise
  return m;
}

TEST(TriangleMesh, TetrahedronIsClosedAndConsistent) {
  const EdgeStatistics s = edge_statistics(tetrahedron());
  EXPECT_EQ(s.edges, 6u);
  EXPECT_TRUE(s.closed());
  EXPECT_EQ(s.inconsistent_edges, 0u);
}

TEST(TriangleMesh, DetectsBoundaryNonManifoldAndFlippedFaces) {
  TriangleMesh m = tetrahedron();
  m.triangles[3] = {1, 3, 2};  // flipped
  EXPECT_EQ(edge_statistics(m).inconsistent_edges, 3u);
  m.triangles.pop_back();
  EXPECT_EQ(edge_statistics(m).boundary_edges, 3u);
  TriangleMesh fan;
  fan.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  fan.triangles = {{0, 1, 2}, {0, 1, 3}, {0, 1, 4}};  // edge 0-1 has three faces
  EXPECT_EQ(edge_statistics(fan).non_manifold_edges, 1u);
}

TEST(TriangleMesh, VertexNormalsPointOutwardOnATetrahedron) {
  TriangleMesh m = tetrahedron();
  compute_vertex_normals(m);
  const Eigen::Vector3f centroid(0.25f, 0.25f, 0.25f);
  for (std::size_t i = 0; i < m.vertices.size(); ++i) {
    EXPECT_NEAR(m.normals[i].norm(), 1.0f, 1e-5f);
    EXPECT_GT(m.normals[i].dot(m.vertices[i] - centroid), 0.0f);
  }
  EXPECT_TRUE(face_normal(m, m.triangles[0]).isApprox(Eigen::Vector3f(0, 0, -1)));
}

}  // namespace
}  // namespace meshflow
