#include <gtest/gtest.h>

#include <cmath>

#include <random>

#include "fixtures/mesh_fixtures.h"
#include "nodes/eval/surface_eval.h"
#include "nodes/extract/marching_cubes.h"
#include "nodes/io/mesh_writers.h"
#include "nodes/io/ply_reader.h"
#include "nodes/search/closest_point.h"
#include "nodes/search/mesh_distance_index.h"
#include "nodes/synthetic/shapes.h"
#include "runtime/error.h"
#include "test_support.h"

namespace meshflow {
namespace {

TEST(SurfaceEval, DistanceStatsOfAKnownList) {
  std::vector<float> d;
  for (int i = 1; i <= 100; ++i) d.push_back(static_cast<float>(i));
  const DistanceStats s = distance_stats(d);
  EXPECT_DOUBLE_EQ(s.mean, 50.5);
  EXPECT_DOUBLE_EQ(s.max, 100.0);
  EXPECT_DOUBLE_EQ(s.p95, 95.0);
  EXPECT_NEAR(s.rms, std::sqrt(338350.0 / 100.0), 1e-9);
  EXPECT_EQ(s.samples, 100u);
}

TEST(SurfaceEval, TopologyCountsLoopsAndDegenerateFaces) {
  const MeshTopology open = mesh_topology(test::grid_patch(4, false));
  EXPECT_EQ(open.boundary_loops, 1u);
  EXPECT_EQ(open.edges.boundary_edges, 16u);
  EXPECT_EQ(open.degenerate_faces, 0u);
  TriangleMesh holed = test::grid_patch(4, true);
  EXPECT_EQ(mesh_topology(holed).boundary_loops, 2u);
  holed.triangles.push_back({0, 1, 2});  // collinear: zero area (and a non-manifold edge)
  holed.triangles.push_back({3, 3, 4});
  EXPECT_EQ(mesh_topology(holed).degenerate_faces, 2u);
}

TEST(SurfaceEval, PatchAgainstItselfAndAgainstAShiftedCopy) {
  const TriangleMesh patch = test::grid_patch(8, false);
  const SurfaceEvaluation same = evaluate_surface(patch, patch);
  EXPECT_EQ(same.mesh_to_reference.max, 0.0);
  EXPECT_EQ(same.reference_to_mesh.max, 0.0);
  EXPECT_NEAR(same.normal_mean_deg, 0.0, 1e-3);
  EXPECT_EQ(same.triangles, 128u);
  TriangleMesh shifted = patch;
  for (auto& v : shifted.vertices) v.z() += 0.01f;
  const SurfaceEvaluation e = evaluate_surface(shifted, patch);
  EXPECT_NEAR(e.mesh_to_reference.mean, 0.01, 1e-6);
  EXPECT_NEAR(e.reference_to_mesh.p95, 0.01, 1e-6);
  // As a point set (no triangles), the reference gives point-to-point distances.
  TriangleMesh points = patch;
  points.triangles.clear();
  EXPECT_NEAR(evaluate_surface(shifted, points).mesh_to_reference.max, 0.01, 1e-6);
  EXPECT_THROW(evaluate_surface(TriangleMesh{}, patch), Error);
  EXPECT_THROW(evaluate_surface(patch, TriangleMesh{}), Error);
}

TEST(SurfaceEval, AnInsideOutMeshIsToldByItsFacesAndItsVolume) {
  const TriangleMesh tet = test::tetrahedron();
  EXPECT_NEAR(signed_volume(tet), 1.0 / 6.0, 1e-9);
  TriangleMesh flipped = tet;
  for (Triangle& t : flipped.triangles) std::swap(t[1], t[2]);
  EXPECT_NEAR(signed_volume(flipped), -1.0 / 6.0, 1e-9);
  // Against the mesh itself (face normals) and a point set with outward normals.
  EXPECT_NEAR(evaluate_surface(tet, tet).inside_out_area_share, 0.0, 1e-9);
  EXPECT_NEAR(evaluate_surface(flipped, tet).inside_out_area_share, 1.0, 1e-9);
  TriangleMesh points;
  for (const Triangle& t : tet.triangles) {
    points.vertices.push_back((tet.vertices[t[0]] + tet.vertices[t[1]] + tet.vertices[t[2]]) / 3);
    points.normals.push_back(face_normal(tet, t));
  }
  EXPECT_NEAR(evaluate_surface(tet, points).inside_out_area_share, 0.0, 1e-9);
  EXPECT_NEAR(evaluate_surface(flipped, points).inside_out_area_share, 1.0, 1e-9);
  points.normals.clear();
  EXPECT_TRUE(std::isnan(evaluate_surface(tet, points).inside_out_area_share));
}

}  // namespace
}  // namespace meshflow
