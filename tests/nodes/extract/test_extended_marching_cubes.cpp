#include "nodes/extract/extended_marching_cubes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <set>

#include "fixtures/solid_fixture.h"
#include "nodes/eval/surface_eval.h"
#include "nodes/extract/feature_edge_flips.h"
#include "nodes/search/mesh_distance_index.h"
#include "runtime/threads.h"
#include "test_support.h"

namespace meshflow {
namespace {

constexpr float kEmcVoxel = 0.05f;

TriangleMesh emc_of(const test::SampledSolid& s, const ExtendedMcConfig& emc = {}) {
  return extended_marching_cubes(s.grid, s.field, s.solid.samples, *s.index, ExtractConfig{}, emc);
}

TEST(SharpFeature, TwoPlanesMeetInAnEdgeAndThreeInACorner) {
  const Eigen::AlignedBox3f cell(Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(1, 1, 1));
  // Planes x = 0.6 (normal +x) and y = 0.3 (normal +y): the feature line is x = 0.6, y = 0.3.
  const std::vector<Eigen::Vector3f> points = {
      {0.6f, 0.0f, 0.2f}, {0.6f, 0.1f, 0.9f}, {0.9f, 0.3f, 0.1f}, {1.0f, 0.3f, 0.7f}};
  const std::vector<Eigen::Vector3f> normals = {Eigen::Vector3f::UnitX(), Eigen::Vector3f::UnitX(),
                                                Eigen::Vector3f::UnitY(), Eigen::Vector3f::UnitY()};
  const FeaturePoint edge = sharp_feature(points.data(), normals.data(), 4, cell);
  ASSERT_EQ(edge.kind, FeatureKind::kEdge);
  EXPECT_NEAR(edge.position.x(), 0.6f, 1e-5f);
  EXPECT_NEAR(edge.position.y(), 0.3f, 1e-5f);
  EXPECT_NEAR(edge.position.z(), 0.475f, 1e-5f);  // the centroid's height: nearest on the line

  auto with_z = points;
  auto with_z_normals = normals;
  with_z.emplace_back(0.2f, 0.1f, 0.45f);  // plane z = 0.45, normal +z
  with_z_normals.push_back(Eigen::Vector3f::UnitZ());
  const FeaturePoint corner = sharp_feature(with_z.data(), with_z_normals.data(), 5, cell);
  ASSERT_EQ(corner.kind, FeatureKind::kCorner);
  EXPECT_LT((corner.position - Eigen::Vector3f(0.6f, 0.3f, 0.45f)).norm(), 1e-5f);

  // A flat patch (normals 10 degrees apart at most) has no feature.
  const std::vector<Eigen::Vector3f> flat = {Eigen::Vector3f::UnitZ(),
                                             Eigen::Vector3f(0.17f, 0, 0.98f).normalized()};
  EXPECT_EQ(sharp_feature(points.data(), flat.data(), 2, cell).kind, FeatureKind::kNone);
}

TEST(SharpFeature, FeaturesFarOutsideTheCellAreRejectedAndNearOnesClamped) {
  const Eigen::AlignedBox3f cell(Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(1, 1, 1));
  const std::vector<Eigen::Vector3f> normals = {Eigen::Vector3f::UnitX(), Eigen::Vector3f::UnitY()};
  // The planes x = 1.1, y = 0.5 meet 0.1 outside the cell: clamped onto its face.
  const std::vector<Eigen::Vector3f> near = {{1.1f, 0.2f, 0.5f}, {0.5f, 0.5f, 0.5f}};
  const FeaturePoint clamped = sharp_feature(near.data(), normals.data(), 2, cell);
  ASSERT_EQ(clamped.kind, FeatureKind::kEdge);
  EXPECT_FLOAT_EQ(clamped.position.x(), 1.0f);
  // x = 3 is two cells away: rejected.
  const std::vector<Eigen::Vector3f> far = {{3.0f, 0.2f, 0.5f}, {0.5f, 0.5f, 0.5f}};
  EXPECT_EQ(sharp_feature(far.data(), normals.data(), 2, cell).kind, FeatureKind::kNone);
}

TEST(DirectedDistance, HitsTheDiskPlaneExactlyAndSkipsDisksFacingTheWrongWay) {
  // Points on the plane x = 0.337, normals +x; a grid edge along x from 0.3 to 0.35.
  PointCloud cloud;
  for (int i = -3; i <= 3; ++i)
    for (int j = -3; j <= 3; ++j) {
      cloud.positions.emplace_back(0.337f, 0.01f * static_cast<float>(i),
                                   0.01f * static_cast<float>(j));
      cloud.normals.push_back(Eigen::Vector3f::UnitX());
    }
  const KdTreeIndex index(cloud.positions);
  const Eigen::Vector3f lower(0.3f, 0.002f, -0.003f), guess(0.32f, 0.002f, -0.003f);
  const EdgeHit hit =
      directed_edge_hit(lower, 0, kEmcVoxel, true, guess, 0.0f, cloud, index, kEmcVoxel);
  EXPECT_TRUE(hit.from_disk);
  EXPECT_NEAR(hit.position.x(), 0.337f, 1e-6f);
  EXPECT_FLOAT_EQ(hit.position.y(), lower.y());
  EXPECT_EQ(hit.normal, Eigen::Vector3f::UnitX());
  // Entering the solid along +x needs normals pointing -x: none qualify, the guess stays.
  const EdgeHit wrong =
      directed_edge_hit(lower, 0, kEmcVoxel, false, guess, 0.0f, cloud, index, kEmcVoxel);
  EXPECT_FALSE(wrong.from_disk);
  EXPECT_EQ(wrong.position, guess);
  // An edge along y is parallel to the disks: no hit.
  EXPECT_FALSE(
      directed_edge_hit(lower, 1, kEmcVoxel, true, guess, 0.0f, cloud, index, kEmcVoxel).from_disk);
}

TEST(ExtendedMarchingCubes, ClosedOrientedAndNearTheSurfaceOnEveryShape) {
  for (const auto& named : test::test_solids(kEmcVoxel)) {
    SCOPED_TRACE(named.name);
    const auto s = test::sampled_solid(named.solid, kEmcVoxel);
    const TriangleMesh emc = emc_of(s);
    const TriangleMesh mc = marching_cubes(s.grid, s.field);
    ASSERT_GT(emc.triangles.size(), 100u);
    const MeshTopology topology = mesh_topology(emc);
    EXPECT_TRUE(topology.edges.closed()) << topology.edges.boundary_edges << " boundary, "
                                         << topology.edges.non_manifold_edges << " non-manifold";
    EXPECT_EQ(topology.edges.inconsistent_edges, 0u);
    EXPECT_EQ(topology.degenerate_faces, 0u);
    // Shared vertices: no two at the same position.
    std::vector<std::array<float, 3>> keys;
    for (const auto& v : emc.vertices) keys.push_back({v.x(), v.y(), v.z()});
    std::sort(keys.begin(), keys.end());
    EXPECT_EQ(std::adjacent_find(keys.begin(), keys.end()), keys.end());
    std::vector<float> emc_error, mc_error;
    for (const auto& v : emc.vertices) emc_error.push_back(std::abs(s.solid.sdf(v)) / kEmcVoxel);
    for (const auto& v : mc.vertices) mc_error.push_back(std::abs(s.solid.sdf(v)) / kEmcVoxel);
    const DistanceStats e = distance_stats(emc_error), m = distance_stats(mc_error);
    std::printf(
        "[ emc ] %s: %zu triangles (mc %zu); |sdf| of vertices mean %.4f max %.4f voxel "
        "(mc mean %.4f max %.4f)\n",
        named.name.c_str(), emc.triangles.size(), mc.triangles.size(), e.mean, e.max, m.mean,
        m.max);
    EXPECT_LT(e.mean, m.mean);
    EXPECT_LT(e.mean, 0.02);
  }
}

// Distances (voxels) from points every 0.05 voxel along the box's 12 edges to the mesh surface,
// and from the 8 corners to the nearest mesh vertex.
struct BoxFeatureError {
  DistanceStats edges, corners;
};

BoxFeatureError box_feature_error(const TriangleMesh& mesh, const Eigen::Vector3f& center,
                                  const Eigen::Vector3f& half) {
  const MeshDistanceIndex surface(mesh);
  std::vector<float> edge_error, corner_error;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3f sign(c & 1 ? 1.f : -1.f, c & 2 ? 1.f : -1.f, c & 4 ? 1.f : -1.f);
    const Eigen::Vector3f corner = center + sign.cwiseProduct(half);
    float nearest = std::numeric_limits<float>::infinity();
    for (const auto& v : mesh.vertices) nearest = std::min(nearest, (v - corner).norm());
    corner_error.push_back(nearest / kEmcVoxel);
    for (int axis = 0; axis < 3; ++axis) {
      if (sign[axis] > 0) continue;  // each edge once, from its lower corner
      for (float t = 0.0f; t <= 2.0f * half[axis]; t += 0.05f * kEmcVoxel) {
        Eigen::Vector3f p = corner;
        p[axis] += t;
        edge_error.push_back(surface.closest(p).distance / kEmcVoxel);
      }
    }
  }
  return {distance_stats(edge_error), distance_stats(corner_error)};
}

TEST(ExtendedMarchingCubes, KeepsTheBoxEdgesAndCornersWhereMarchingCubesRoundsThem) {
  const Eigen::Vector3f center(0.013f, -0.021f, 0.007f), half(0.4f, 0.4f, 0.4f);
  const auto s = test::sampled_solid(test::test_solids(kEmcVoxel)[0].solid, kEmcVoxel);
  const BoxFeatureError emc = box_feature_error(emc_of(s), center, half);
  const BoxFeatureError mc = box_feature_error(marching_cubes(s.grid, s.field), center, half);
  ExtendedMcConfig no_flips;
  no_flips.flip_edges = false;
  const BoxFeatureError fans_only = box_feature_error(emc_of(s, no_flips), center, half);
  std::printf(
      "[ emc ] box edges to mesh (voxels): emc mean %.4f p95 %.4f max %.4f; fans only "
      "mean %.4f p95 %.4f; mc mean %.4f p95 %.4f\n",
      emc.edges.mean, emc.edges.p95, emc.edges.max, fans_only.edges.mean, fans_only.edges.p95,
      mc.edges.mean, mc.edges.p95);
  std::printf("[ emc ] box corners to nearest vertex (voxels): emc max %.4f; mc mean %.4f\n",
              emc.corners.max, mc.corners.mean);
  EXPECT_LT(emc.edges.p95, 0.05);
  EXPECT_LT(emc.corners.max, 0.05);
  EXPECT_GT(mc.edges.mean, 0.1);
  EXPECT_GT(mc.corners.mean, 0.2);
  EXPECT_LT(emc.edges.mean, fans_only.edges.mean);  // the flips run along the edges
}

TEST(ExtendedMarchingCubes, SameOutputWithOneAndTwoThreads) {
  const auto s = test::sampled_solid(test::test_solids(kEmcVoxel)[2].solid, kEmcVoxel);
  const TriangleMesh one = test::with_threads(1, [&] { return emc_of(s); });
  const TriangleMesh two = test::with_threads(2, [&] { return emc_of(s); });
  EXPECT_GT(one.triangles.size(), 100u);
  EXPECT_EQ(one.vertices, two.vertices);
  EXPECT_EQ(one.triangles, two.triangles);
}

// The out-of-core path flips on the welded mesh, numbered otherwise than one process's: the
// flips must not depend on the vertex numbers. The deferred pass on a renumbered mesh gives
// the triangles of the pass inside extraction, and the feature vertices reported are the
// ones it flipped between.
TEST(ExtendedMarchingCubes, EdgeFlipsDoNotDependOnTheVertexNumbering) {
  const auto s = test::sampled_solid(test::test_solids(kEmcVoxel)[0].solid, kEmcVoxel);
  std::vector<std::uint8_t> features;
  const TriangleMesh flipped = extended_marching_cubes(s.grid, s.field, s.solid.samples, *s.index,
                                                       ExtractConfig{}, {}, &features);
  ExtendedMcConfig deferred;
  deferred.flip_edges = false;
  std::vector<std::uint8_t> deferred_features;
  const TriangleMesh fans = extended_marching_cubes(s.grid, s.field, s.solid.samples, *s.index,
                                                    ExtractConfig{}, deferred, &deferred_features);
  ASSERT_EQ(features, deferred_features);
  ASSERT_GT(std::count(features.begin(), features.end(), 1), 10);
  // Renumber: vertices reversed, triangles reversed.
  const std::size_t n = fans.vertices.size();
  TriangleMesh renumbered;
  std::vector<std::uint8_t> renumbered_features(n);
  for (std::size_t v = 0; v < n; ++v) {
    renumbered.vertices.push_back(fans.vertices[n - 1 - v]);
    renumbered_features[v] = features[n - 1 - v];
  }
  for (auto t = fans.triangles.rbegin(); t != fans.triangles.rend(); ++t)
    renumbered.triangles.push_back({static_cast<std::uint32_t>(n - 1 - (*t)[0]),
                                    static_cast<std::uint32_t>(n - 1 - (*t)[1]),
                                    static_cast<std::uint32_t>(n - 1 - (*t)[2])});
  const std::size_t flips = flip_edges_between_features(renumbered, renumbered_features);
  EXPECT_GT(flips, 10u);
  const auto corners = [](const TriangleMesh& m) {
    std::multiset<std::array<float, 9>> out;
    for (const Triangle& t : m.triangles) {
      std::array<std::size_t, 3> order{0, 1, 2};
      const std::size_t first = static_cast<std::size_t>(
          std::min_element(t.begin(), t.end(),
                           [&](std::uint32_t a, std::uint32_t b) {
                             const auto& p = m.vertices[a];
                             const auto& q = m.vertices[b];
                             return std::lexicographical_compare(p.data(), p.data() + 3, q.data(),
                                                                 q.data() + 3);
                           }) -
          t.begin());
      std::array<float, 9> key;
      for (std::size_t k = 0; k < 3; ++k)
        for (int a = 0; a < 3; ++a) key[3 * k + a] = m.vertices[t[(first + order[k]) % 3]][a];
      out.insert(key);
    }
    return out;
  };
  EXPECT_EQ(corners(renumbered), corners(flipped));
}

}  // namespace
}  // namespace meshflow
