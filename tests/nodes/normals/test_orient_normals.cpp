// Orientation by propagation: closed solids sampled without normals or a sensor, against their
// exact outward normals.

#include "nodes/normals/orient_normals.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "nodes/normals/normals.h"
#include "nodes/synthetic/closed_objects.h"
#include "nodes/synthetic/depth_sequence.h"
#include "nodes/synthetic/scan_simulator.h"
#include "runtime/threads.h"
#include "test_support.h"

namespace meshflow {
namespace {

// Share of `normals` within 90 degrees of `truth`.
double share_agreeing(const std::vector<Eigen::Vector3f>& normals,
                      const std::vector<Eigen::Vector3f>& truth) {
  std::size_t agree = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) agree += normals[i].dot(truth[i]) > 0.0f ? 1 : 0;
  return static_cast<double>(agree) / static_cast<double>(truth.size());
}

// Unit normals of `cloud` estimated and oriented by propagation (cloud.normals ignored).
ComputedNormals propagated_normals(PointCloud cloud) {
  cloud.normals.clear();
  const KdTreeIndex index(cloud.positions);
  NormalsConfig config;
  config.orientation = NormalOrientation::kPropagate;
  return compute_normals(cloud, index, config);
}

class ClosedSolid : public ::testing::TestWithParam<int> {
 protected:
  synthetic::ClosedObject object() const {
    return synthetic::closed_test_objects()[static_cast<std::size_t>(GetParam())];
  }
};

TEST_P(ClosedSolid, PropagatedNormalsPointOutward) {
  const synthetic::ClosedObject solid = object();
  const PointCloud samples = solid.sample(30000, 0.0f, 11);
  const ComputedNormals computed = propagated_normals(samples);
  EXPECT_GE(share_agreeing(computed.normals, samples.normals), 0.999) << solid.name;
  EXPECT_EQ(computed.report.orientation, NormalOrientation::kPropagate);
  EXPECT_EQ(computed.report.components, 1u) << solid.name;
  EXPECT_EQ(computed.report.estimated, samples.size());
}

TEST_P(ClosedSolid, NoisySamplesStillPointOutward) {
  // Noise of 0.2 of a voxel of 1 % of the diagonal, as in the reconstruction tests.
  const synthetic::ClosedObject solid = object();
  const PointCloud samples = solid.sample(100000, 0.002f * solid.diagonal(), 12);
  // Plane fits on noisy points can be off by more than 90 degrees whatever the orientation;
  // the bound is on orientation mistakes, which would flip whole regions.
  EXPECT_GE(share_agreeing(propagated_normals(samples).normals, samples.normals), 0.99)
      << solid.name;
}

INSTANTIATE_TEST_SUITE_P(Objects, ClosedSolid, ::testing::Range(0, 6),
                         [](const ::testing::TestParamInfo<int>& param) {
                           return test::closed_object_test_name(param.param);
                         });

TEST(OrientNormals, SameSignsWithOneAndTwoThreads) {
  PointCloud cloud = synthetic::box_with_hole_object().sample(20000, 0.001f, 3);
  std::vector<Eigen::Vector3f> one, two;
  {
    ThreadLimit limit(1);
    one = propagated_normals(cloud).normals;
  }
  {
    ThreadLimit limit(2);
    two = propagated_normals(cloud).normals;
  }
  EXPECT_EQ(one.size(), cloud.size());
  EXPECT_EQ(one, two);
}

TEST(OrientNormals, TwoSeparateObjectsAreEachTurnedOutward) {
  PointCloud a = synthetic::sphere_object().sample(8000, 0.0f, 4);
  PointCloud b = synthetic::torus_object().sample(8000, 0.0f, 5);
  for (Eigen::Vector3f& p : b.positions) p.x() += 3.0f;
  a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
  a.normals.insert(a.normals.end(), b.normals.begin(), b.normals.end());
  const ComputedNormals computed = propagated_normals(a);
  EXPECT_EQ(computed.report.components, 2u);
  EXPECT_GE(share_agreeing(computed.normals, a.normals), 0.999);
}

TEST(OrientNormals, TheWallOfACavityFacesIntoIt) {
  // A hollow ball: the outer sphere (radius 0.5) faces out, the cavity's wall (radius 0.45, a
  // separate component) faces into the cavity, towards its own centroid.
  synthetic::ClosedObject hollow = synthetic::sphere_object();
  synthetic::SurfacePatch cavity = hollow.patches[0];
  const Eigen::Vector3f centre = hollow.bounds.center();
  cavity.area *= 0.45 * 0.45 / 0.25;
  cavity.draw = [outer = hollow.patches[0].draw, centre](std::mt19937_64& rng, Eigen::Vector3f& p,
                                                         Eigen::Vector3f& n) {
    outer(rng, p, n);
    p = centre + 0.9f * (p - centre);
    n = -n;
  };
  hollow.patches.push_back(cavity);
  const PointCloud samples = hollow.sample(40000, 0.0f, 9);
  const ComputedNormals computed = propagated_normals(samples);
  EXPECT_EQ(computed.report.components, 2u);
  EXPECT_GE(share_agreeing(computed.normals, samples.normals), 0.999);
}

TEST(OrientNormals, FixedPointsKeepTheirSignAndTheRestFollow) {
  // Every normal of the sphere turned inward: with a quarter of them fixed, the others follow
  // the fixed ones, not the outward rule.
  const PointCloud samples = synthetic::sphere_object().sample(10000, 0.0f, 6);
  const KdTreeIndex index(samples.positions);
  const NeighbourTable table = build_neighbour_table(samples.positions, index, 10);
  std::vector<Eigen::Vector3f> scrambled(samples.size());
  std::vector<std::uint8_t> fixed(samples.size(), 0);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    fixed[i] = i % 4 == 0 ? 1 : 0;
    scrambled[i] =
        (fixed[i] || i % 3 == 0) ? Eigen::Vector3f(-samples.normals[i]) : samples.normals[i];
  }
  const OrientedNormals out =
      orient_by_propagation(samples.positions, scrambled, table, fixed, PropagationConfig{});
  for (std::size_t i = 0; i < samples.size(); ++i)
    ASSERT_LT(out.normals[i].dot(samples.normals[i]), 0.0f) << "point " << i;
}

TEST(OrientNormals, AnOpenSheetIsConsistent) {
  // A wavy open sheet: no inside, but one orientation throughout.
  PointCloud sheet;
  for (int i = 0; i < 120; ++i)
    for (int j = 0; j < 120; ++j) {
      const float x = 0.01f * static_cast<float>(i), y = 0.01f * static_cast<float>(j);
      sheet.positions.emplace_back(x, y, 0.1f * std::sin(6.0f * x) * std::cos(4.0f * y));
    }
  const ComputedNormals computed = propagated_normals(sheet);
  std::size_t up = 0;
  for (const Eigen::Vector3f& n : computed.normals) up += n.z() > 0.0f ? 1 : 0;
  EXPECT_TRUE(up == 0 || up == sheet.size()) << up << " of " << sheet.size() << " face up";
}

TEST(OrientNormals, EmptyAndTinyInputs) {
  const NeighbourTable empty_table;
  EXPECT_TRUE(orient_by_propagation({}, {}, empty_table, {}, PropagationConfig{}).normals.empty());
  PointCloud three;
  three.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const ComputedNormals computed = propagated_normals(three);
  ASSERT_EQ(computed.normals.size(), 3u);
  for (const Eigen::Vector3f& n : computed.normals) EXPECT_NEAR(std::abs(n.z()), 1.0f, 1e-5f);
}

// A camera-frame cloud as Open3D (remove_non_finite_points, write_point_cloud) or PCL write
// one: the organized frame's finite points, no grid, no sensor position, no normals.
PointCloud written_without_sensor(const PointCloud& organized) {
  std::vector<std::uint32_t> finite;
  for (std::size_t i = 0; i < organized.size(); ++i)
    if (organized.positions[i].allFinite()) finite.push_back(static_cast<std::uint32_t>(i));
  PointCloud cloud = select_points(organized, finite);
  cloud.has_sensor_origin = false;
  cloud.sensor_origin = Eigen::Vector3f::Zero();
  cloud.normals.clear();
  return cloud;
}

// Share of the normals facing `point` (n . (point - p) > 0).
double share_facing(const PointCloud& cloud, const std::vector<Eigen::Vector3f>& normals,
                    const Eigen::Vector3f& point) {
  std::size_t facing = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i)
    facing += normals[i].dot(point - cloud.positions[i]) > 0.0f ? 1 : 0;
  return static_cast<double>(facing) / static_cast<double>(cloud.size());
}

// Share of the normals with a positive z.
double share_up(const std::vector<Eigen::Vector3f>& normals) {
  std::size_t up = 0;
  for (const Eigen::Vector3f& n : normals) up += n.z() > 0.0f ? 1 : 0;
  return static_cast<double>(up) / static_cast<double>(normals.size());
}

ComputedNormals normals_as(const PointCloud& cloud, const NormalsConfig& config) {
  const KdTreeIndex index(cloud.positions);
  return compute_normals(cloud, index, config);
}

// A hilly terrain tile of 60 x 60 m, heights around 30 m, as an airborne LAS gives it.
PointCloud terrain_tile(bool z_up) {
  PointCloud tile;
  for (int i = 0; i < 150; ++i)
    for (int j = 0; j < 150; ++j) {
      const float x = 0.4f * static_cast<float>(i), y = 0.4f * static_cast<float>(j);
      tile.positions.emplace_back(x, y, 30.0f + 3.0f * std::sin(0.2f * x) * std::cos(0.15f * y));
    }
  tile.z_up = z_up;
  return tile;
}

// Issue 55: inside a room, outward from the points' centroid is away from the camera; a cloud
// in its camera's frame must face the camera at the origin without being told.
TEST(SceneSide, OneCameraViewWithoutASensorFacesTheCamera) {
  synthetic::DepthSequenceConfig camera;
  camera.frames = 4;
  camera.intrinsics = synthetic::scaled_default_camera(160, 120);
  const auto sequence = synthetic::make_depth_sequence(synthetic::demo_room_scene(), camera);
  for (std::size_t f = 0; f < 2; ++f) {
    const PointCloud cloud =
        written_without_sensor(test::camera_frame_cloud(sequence->frame(f).load_depth()));
    ASSERT_GT(cloud.size(), 10000u);
    EXPECT_TRUE(looks_like_camera_view(cloud));
    const ComputedNormals computed = normals_as(cloud, NormalsConfig{});
    EXPECT_EQ(computed.report.orientation, NormalOrientation::kPropagate);
    EXPECT_EQ(computed.report.side, ComponentSide::kTowardPoint);
    EXPECT_GE(share_facing(cloud, computed.normals, Eigen::Vector3f::Zero()), 0.97)
        << "frame " << f;
    std::printf("[ camera view ] frame %zu: agreement %.3f\n", f, computed.report.view_agreement);
  }
}

// A closed object in front of the origin passes the camera's geometric test, but its normals
// do not agree on facing the origin: it stays outward.
TEST(SceneSide, AClosedObjectInFrontOfTheOriginStaysOutward) {
  for (const synthetic::ClosedObject& solid :
       {synthetic::sphere_object(), synthetic::chamfered_cube_object()}) {
    PointCloud samples = solid.sample(30000, 0.0f, 5);
    for (Eigen::Vector3f& p : samples.positions) p += Eigen::Vector3f(0.2f, 0.1f, 3.0f);
    const std::vector<Eigen::Vector3f> truth = samples.normals;
    samples.normals.clear();
    EXPECT_TRUE(looks_like_camera_view(samples)) << solid.name;
    const ComputedNormals computed = normals_as(samples, NormalsConfig{});
    EXPECT_EQ(computed.report.side, ComponentSide::kOutward) << solid.name;
    std::printf("[ closed object ] %s: agreement %.3f\n", solid.name.c_str(),
                computed.report.view_agreement);
    EXPECT_GE(share_agreeing(computed.normals, truth), 0.999) << solid.name;
  }
}

// LAS heights: the terrain faces up wherever the origin is (here below it, where "towards the
// origin" would turn it down, and with the centroid's rule indecisive on an open sheet).
TEST(SceneSide, LasTerrainFacesUp) {
  const PointCloud tile = terrain_tile(true);
  EXPECT_EQ(scene_side(tile), ComponentSide::kAlongAxis);
  const ComputedNormals computed = normals_as(tile, NormalsConfig{});
  EXPECT_EQ(computed.report.side, ComponentSide::kAlongAxis);
  EXPECT_STREQ(side_name(computed.report.side, computed.report.side_axis), "up");
  EXPECT_GE(share_up(computed.normals), 0.999);
  // Without the LAS flag this tile (its origin a corner below it, points up to 85 degrees off
  // the z axis) is no camera view either.
  EXPECT_FALSE(looks_like_camera_view(terrain_tile(false)));
}

// A 60 x 60 m valley, heights 0-36 m (slopes up to 50 degrees), in local coordinates: outward
// from the centroid (which lies above the valley floor) would face it down.
PointCloud valley_tile() {
  PointCloud tile;
  for (int i = 0; i < 150; ++i)
    for (int j = 0; j < 150; ++j) {
      const float x = 0.4f * static_cast<float>(i) - 30.0f,
                  y = 0.4f * static_cast<float>(j) - 30.0f;
      tile.positions.emplace_back(x, y, 0.02f * (x * x + y * y) + 0.3f * std::sin(x));
    }
  return tile;
}

// Issue 55: a terrain tile in local coordinates (no LAS flag, no map offset) is one surface over
// x-y: it faces up without a flag, and the report says why.
TEST(SceneSide, ATerrainTileInLocalCoordinatesFacesUp) {
  for (const PointCloud& tile : {terrain_tile(false), valley_tile()}) {
    EXPECT_TRUE(looks_like_height_field(tile));
    EXPECT_EQ(classify_scene(tile), SceneKind::kHeightField);
    const ComputedNormals computed = normals_as(tile, NormalsConfig{});
    EXPECT_EQ(computed.report.scene, SceneKind::kHeightField);
    EXPECT_EQ(computed.report.side, ComponentSide::kAlongAxis);
    EXPECT_GE(computed.report.view_agreement, 0.9);
    EXPECT_GE(share_up(computed.normals), 0.999);
    // A piece of a larger cloud (an out-of-core chunk) decides nothing from its own geometry.
    EXPECT_EQ(classify_scene(tile, false), SceneKind::kObject);
  }
}

// Closed objects cross every column twice, so they are no height fields; the thin plate lying
// flat (2 cm thick) is one by its geometry, but its normals cancel on up: outward still.
TEST(SceneSide, ClosedObjectsAreNoTerrain) {
  for (const synthetic::ClosedObject& solid : synthetic::all_test_objects()) {
    const PointCloud samples = solid.sample(30000, 0.0f, 5);
    const SceneKind kind = classify_scene(samples);
    if (solid.name != "thin-plate") {
      EXPECT_EQ(kind, SceneKind::kObject) << solid.name;
    }
    if (kind != SceneKind::kHeightField) continue;
    PointCloud without = samples;
    without.normals.clear();
    const ComputedNormals computed = normals_as(without, NormalsConfig{});
    EXPECT_EQ(computed.report.side, ComponentSide::kOutward) << solid.name;
    EXPECT_LT(computed.report.view_agreement, 0.5) << solid.name;
  }
  // Too few points to tell.
  PointCloud few;
  for (int i = 0; i < 40; ++i) few.positions.emplace_back(0.1f * static_cast<float>(i), 0.0f, 0.0f);
  EXPECT_FALSE(looks_like_height_field(few));
}

TEST(SceneSide, UpDownAndFlipAreTheUsersChoice) {
  const PointCloud tile = terrain_tile(false);
  NormalsConfig config;
  config.orientation = NormalOrientation::kDown;
  EXPECT_LE(share_up(normals_as(tile, config).normals), 0.001);
  config.orientation = NormalOrientation::kUp;
  EXPECT_GE(share_up(normals_as(tile, config).normals), 0.999);
  config.flip = true;  // up, turned over
  const ComputedNormals flipped = normals_as(tile, config);
  EXPECT_TRUE(flipped.report.flipped);
  EXPECT_LE(share_up(flipped.normals), 0.001);
  // The input's own normals are turned over too.
  PointCloud with_normals = tile;
  with_normals.normals.assign(tile.size(), Eigen::Vector3f::UnitZ());
  NormalsConfig flip_only;
  flip_only.flip = true;
  const ComputedNormals input = normals_as(with_normals, flip_only);
  EXPECT_EQ(input.report.source, NormalSource::kInput);
  EXPECT_LE(share_up(input.normals), 0.0);
}

// `--orient viewpoint=X,Y,Z` on a georeferenced cloud names a point in world coordinates.
TEST(SceneSide, AViewpointIsInTheFilesOwnCoordinates) {
  PointCloud tile = terrain_tile(true);
  tile.origin = Eigen::Vector3d(512000.0, 5403000.0, 0.0);  // a UTM tile's local frame
  NormalsConfig config;
  config.orientation = NormalOrientation::kTowardViewpoint;
  config.viewpoint = Eigen::Vector3f(512030.0f, 5403030.0f, 1000.0f);  // above the tile
  EXPECT_GE(share_up(normals_as(tile, config).normals), 0.999);
  config.viewpoint = Eigen::Vector3f(512030.0f, 5403030.0f, -1000.0f);  // below it
  EXPECT_LE(share_up(normals_as(tile, config).normals), 0.001);
}

}  // namespace
}  // namespace meshflow
