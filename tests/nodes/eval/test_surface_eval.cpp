#include <gtest/gtest.h>

#include <cmath>

#include <random>

#include "nodes/eval/closest_point.h"
#include "nodes/eval/mesh_distance_index.h"
#include "nodes/eval/surface_eval.h"
#include "nodes/extract/marching_cubes.h"
#include "nodes/io/mesh_writers.h"
#include "nodes/io/ply_reader.h"
#include "nodes/synthetic/shapes.h"
#include "runtime/error.h"
#include "test_support.h"

namespace meshflow {
namespace {

// A unit square [0,1]^2 at z = 0 split into n x n quads, optionally without the middle quad.
TriangleMesh grid_patch(int n, bool hole) {
  TriangleMesh m;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x)
      m.vertices.emplace_back(static_cast<float>(x) / n, static_cast<float>(y) / n, 0.0f);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      if (hole && x == n / 2 && y == n / 2) continue;
      const auto v = static_cast<std::uint32_t>(y * (n + 1) + x);
      const auto w = static_cast<std::uint32_t>(n + 1);
      m.triangles.push_back({v, v + 1, v + w + 1});
      m.triangles.push_back({v, v + w + 1, v + w});
    }
  return m;
}

TEST(ClosestPoint, MatchesDenseSamplingOfTheTriangle) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3f a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)),
        c(u(rng), u(rng), u(rng)), p(2 * u(rng), 2 * u(rng), 2 * u(rng));
    const Eigen::Vector3f q = closest_point_on_triangle(p, a, b, c);
    float best = std::numeric_limits<float>::max();
    const int n = 200;
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        const Eigen::Vector3f s = a + (b - a) * (float(i) / n) + (c - a) * (float(j) / n);
        best = std::min(best, (s - p).norm());
      }
    EXPECT_LE((q - p).norm(), best + 1e-5f);
    EXPECT_GE((q - p).norm(), best - 0.02f);  // sampling resolution
  }
  // Degenerate (collinear) triangle: the nearest point of the segment.
  const Eigen::Vector3f q =
      closest_point_on_triangle({0.5f, 1.0f, 0.0f}, {0, 0, 0}, {1, 0, 0}, {2, 0, 0});
  EXPECT_NEAR((q - Eigen::Vector3f(0.5f, 0, 0)).norm(), 0.0f, 1e-6f);
}

TEST(MeshDistanceIndex, EqualsBruteForceNearAndFar) {
  const synthetic::Sphere sphere{{0.1f, 0.0f, -0.2f}, 0.6f};
  const TriangleMesh mesh = [&] {
    TriangleMesh m;
    const PointCloud pts = synthetic::sample_surface(sphere, 0.1f, 0.0f, 1);
    // A closed mesh is not needed: a triangle soup of nearby sample triples.
    for (std::size_t i = 0; i + 2 < pts.size(); i += 3) {
      const auto v = static_cast<std::uint32_t>(m.vertices.size());
      m.vertices.push_back(pts.positions[i]);
      m.vertices.push_back(pts.positions[i] + Eigen::Vector3f(0.05f, 0.0f, 0.01f));
      m.vertices.push_back(pts.positions[i] + Eigen::Vector3f(0.0f, 0.04f, -0.02f));
      m.triangles.push_back({v, v + 1, v + 2});
    }
    return m;
  }();
  const MeshDistanceIndex index(mesh);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-3.0f, 3.0f);
  for (int trial = 0; trial < 300; ++trial) {
    const float scale = trial < 150 ? 0.3f : 1.0f;  // near the surface, then far away
    const Eigen::Vector3f p(scale * u(rng), scale * u(rng), scale * u(rng));
    float brute = std::numeric_limits<float>::max();
    for (const Triangle& t : mesh.triangles)
      brute = std::min(brute, (closest_point_on_triangle(p, mesh.vertices[t[0]],
                                                         mesh.vertices[t[1]], mesh.vertices[t[2]]) -
                               p)
                                  .norm());
    EXPECT_FLOAT_EQ(index.closest(p).distance, brute);
  }
}

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
  const MeshTopology open = mesh_topology(grid_patch(4, false));
  EXPECT_EQ(open.boundary_loops, 1u);
  EXPECT_EQ(open.edges.boundary_edges, 16u);
  EXPECT_EQ(open.degenerate_faces, 0u);
  TriangleMesh holed = grid_patch(4, true);
  EXPECT_EQ(mesh_topology(holed).boundary_loops, 2u);
  holed.triangles.push_back({0, 1, 2});  // collinear: zero area (and a non-manifold edge)
  holed.triangles.push_back({3, 3, 4});
  EXPECT_EQ(mesh_topology(holed).degenerate_faces, 2u);
}

TEST(SurfaceEval, PatchAgainstItselfAndAgainstAShiftedCopy) {
  const TriangleMesh patch = grid_patch(8, false);
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

TEST(PlyMeshReader, RoundTripsWrittenMeshesAndRejectsBadFaces) {
  const std::string dir = test::temp_dir();
  TriangleMesh mesh = grid_patch(3, true);
  compute_vertex_normals(mesh);
  for (auto enc : {io::PlyEncoding::kBinary, io::PlyEncoding::kAscii}) {
    io::write_ply(dir + "/m.ply", mesh, enc);
    const TriangleMesh back = io::read_ply_mesh(dir + "/m.ply");
    EXPECT_EQ(back.vertices, mesh.vertices);
    EXPECT_EQ(back.triangles, mesh.triangles);
    EXPECT_EQ(back.normals.size(), mesh.normals.size());
  }
  test::write_file(dir + "/bad.ply",
                   "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                   "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                   "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
  try {
    io::read_ply_mesh(dir + "/bad.ply");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("face 0"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("vertex index"), std::string::npos) << e.what();
  }
  // Point clouds (no face element) read as meshes without triangles.
  test::write_file(dir + "/pts.ply",
                   "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                   "property float z\nend_header\n1 2 3\n");
  EXPECT_TRUE(io::read_ply_mesh(dir + "/pts.ply").triangles.empty());
}

}  // namespace
}  // namespace meshflow
