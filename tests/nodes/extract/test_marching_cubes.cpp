#include "nodes/extract/marching_cubes.h"

#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>

#include "nodes/cube/cube_table.h"
#include "nodes/voxelize/voxelize.h"
#include "runtime/threads.h"

namespace meshflow {
namespace {

// A dense grid over [-n, n]^3 cells of size `voxel` with the field `f` at every corner.
template <typename F>
std::pair<SparseGrid, DistanceField> dense_field(int n, float voxel, F f) {
  PointCloud c;
  for (int z = -n; z < n; ++z)
    for (int y = -n; y < n; ++y)
      for (int x = -n; x < n; ++x)
        c.positions.emplace_back((x + 0.5f) * voxel, (y + 0.5f) * voxel, (z + 0.5f) * voxel);
  SparseGrid grid = voxelize(c, VoxelizeConfig{voxel, 0.0f});
  DistanceField field;
  for (std::size_t i = 0; i < grid.corners.size(); ++i) {
    field.values.push_back(f(grid.corner_position(i), i));
    field.valid.push_back(1);
  }
  return {std::move(grid), std::move(field)};
}

TEST(MarchingCubes, EveryCaseIsAClosedOrientedPatch) {
  // Each case's triangles, as edges between cube-edge ids, must pair up except on cube faces:
  // checked globally below; here: triangle counts are within the classic bounds.
  const auto& cases = cube_cases();
  EXPECT_TRUE(cases[0].triangles.empty());
  EXPECT_TRUE(cases[255].triangles.empty());
  for (int p = 1; p < 255; ++p) {
    EXPECT_GE(cases[static_cast<std::size_t>(p)].triangles.size(), 1u);
    EXPECT_LE(cases[static_cast<std::size_t>(p)].triangles.size(), 12u);
  }
  EXPECT_EQ(cases[1].triangles.size(), 1u);
  EXPECT_EQ(cases[0x0F].triangles.size(), 2u);  // a plane: one quad
}

TEST(MarchingCubes, SphereIsClosedOutwardAndAccurate) {
  const float voxel = 0.05f, radius = 0.71f;
  auto [grid, field] = dense_field(
      20, voxel, [&](const Eigen::Vector3f& p, std::size_t) { return p.norm() - radius; });
  const TriangleMesh mesh = marching_cubes(grid, field);
  const EdgeStatistics stats = edge_statistics(mesh);
  EXPECT_TRUE(stats.closed());
  EXPECT_EQ(stats.inconsistent_edges, 0u);
  double mean = 0.0;
  for (const auto& v : mesh.vertices) mean += std::abs(v.norm() - radius);
  mean /= static_cast<double>(mesh.vertices.size());
  EXPECT_LT(mean, 0.02 * voxel);
  for (const Triangle& t : mesh.triangles) {
    const Eigen::Vector3f centre =
        (mesh.vertices[t[0]] + mesh.vertices[t[1]] + mesh.vertices[t[2]]) / 3.0f;
    EXPECT_GT(face_normal(mesh, t).dot(centre.normalized()), 0.5f);
  }
  // No duplicate vertices: each crossed edge produced exactly one.
  std::set<std::tuple<float, float, float>> unique;
  for (const auto& v : mesh.vertices) unique.insert({v.x(), v.y(), v.z()});
  EXPECT_EQ(unique.size(), mesh.vertices.size());
}

TEST(MarchingCubes, RandomFieldsGiveManifoldCrackFreeSurfaces) {
  // Random signs exercise every case, the ambiguous faces included.
  for (std::uint32_t seed = 1; seed <= 10; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::vector<float> values(20000);
    for (auto& v : values) v = u(rng);
    auto [grid, field] =
        dense_field(6, 1.0f, [&](const Eigen::Vector3f&, std::size_t i) { return values[i]; });
    const TriangleMesh mesh = marching_cubes(grid, field);
    const EdgeStatistics stats = edge_statistics(mesh);
    EXPECT_EQ(stats.non_manifold_edges, 0u);
    EXPECT_EQ(stats.inconsistent_edges, 0u);
    // Open edges may only lie on the outer faces of the grid (|coordinate| == 6).
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
    for (const Triangle& t : mesh.triangles)
      for (int k = 0; k < 3; ++k)
        ++edges[{std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3])}];
    for (const auto& [e, count] : edges) {
      if (count == 2) continue;
      const Eigen::Vector3f a = mesh.vertices[e.first], b = mesh.vertices[e.second];
      bool on_face = false;
      for (int axis = 0; axis < 3; ++axis) {
        on_face |= std::abs(std::abs(a[axis]) - 6.0f) < 1e-4f &&
                   std::abs(std::abs(b[axis]) - 6.0f) < 1e-4f;
      }
      EXPECT_TRUE(on_face) << a.transpose() << " - " << b.transpose();
    }
  }
}

TEST(MarchingCubes, InvalidCornersProduceNoSurface) {
  auto [grid, field] =
      dense_field(4, 1.0f, [](const Eigen::Vector3f& p, std::size_t) { return p.z() - 0.3f; });
  const std::size_t full = marching_cubes(grid, field).triangles.size();
  for (std::size_t i = 0; i < grid.corners.size(); ++i) {
    if (grid.corner_position(i).x() > 0.5f) field.valid[i] = 0;
  }
  const TriangleMesh half = marching_cubes(grid, field);
  EXPECT_GT(half.triangles.size(), 0u);
  EXPECT_LT(half.triangles.size(), full);
  for (const auto& v : half.vertices) EXPECT_LE(v.x(), 0.5f);
}

TEST(MarchingCubes, SameMeshWithOneAndTwoThreads) {
  auto [grid, field] = dense_field(16, 0.1f, [](const Eigen::Vector3f& p, std::size_t) {
    return std::sin(4.0f * p.x()) + std::cos(3.0f * p.y()) - p.z();
  });
  TriangleMesh one, two;
  {
    ThreadLimit limit(1);
    one = marching_cubes(grid, field);
  }
  {
    ThreadLimit limit(2);
    two = marching_cubes(grid, field);
  }
  EXPECT_GT(one.triangles.size(), 100u);
  EXPECT_EQ(one.vertices, two.vertices);
  EXPECT_EQ(one.triangles, two.triangles);
}

}  // namespace
}  // namespace meshflow
