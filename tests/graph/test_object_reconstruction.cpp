// Closed objects scanned without a sensor (parts, CAD checks): sampled uniformly, no normals,
// voxel = 1 % of the bounding-box diagonal, default configuration. The mesh must be watertight,
// face outward and lie on the exact surface.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <limits>

#include "graph/pipeline.h"
#include "nodes/eval/surface_eval.h"
#include "nodes/eval/truth_eval.h"
#include "nodes/extract/marching_cubes.h"
#include "nodes/io/mesh_writers.h"
#include "nodes/io/read_point_cloud.h"
#include "nodes/search/mesh_distance_index.h"
#include "nodes/synthetic/closed_objects.h"
#include "runtime/threads.h"
#include "test_support.h"

namespace meshflow {
namespace {

struct ObjectErrors {
  double mean = 0.0, p95 = 0.0;
};

ObjectErrors object_vertex_errors(const TriangleMesh& mesh, const synthetic::ClosedObject& object) {
  std::vector<float> e;
  e.reserve(mesh.vertices.size());
  for (const Eigen::Vector3f& v : mesh.vertices) e.push_back(object.distance(v));
  ObjectErrors out;
  for (float x : e) out.mean += x;
  out.mean /= static_cast<double>(e.size());
  std::nth_element(e.begin(), e.begin() + static_cast<std::ptrdiff_t>(e.size() * 95 / 100),
                   e.end());
  out.p95 = e[e.size() * 95 / 100];
  return out;
}

// Six times the enclosed volume: positive when the faces wind outward.
double six_times_volume(const TriangleMesh& m) {
  double v = 0.0;
  for (const Triangle& t : m.triangles)
    v += static_cast<double>(m.vertices[t[0]].dot(m.vertices[t[1]].cross(m.vertices[t[2]])));
  return v;
}

ReconstructionConfig object_config(const synthetic::ClosedObject& object) {
  ReconstructionConfig c;
  c.voxelize.voxel_size = 0.01f * object.diagonal();
  return c;
}

FramePtr reconstruct_object(const ReconstructionConfig& config, PointCloud cloud) {
  FramePtr f = ReconstructionPipeline(config).reconstruct(std::move(cloud));
  EXPECT_TRUE(f->ok()) << f->error;
  return f;
}

PointCloud points_only(PointCloud cloud) {
  cloud.normals.clear();
  return cloud;
}

class ClosedObjectReconstruction : public ::testing::TestWithParam<int> {
 protected:
  synthetic::ClosedObject object() const {
    return synthetic::closed_test_objects()[static_cast<std::size_t>(GetParam())];
  }
};

TEST_P(ClosedObjectReconstruction, WatertightOutwardAndOnTheSurface) {
  const synthetic::ClosedObject object = this->object();
  const ReconstructionConfig config = object_config(object);
  const float voxel = config.voxelize.voxel_size;
  const FramePtr f = reconstruct_object(config, points_only(object.sample(100000, 0.0f, 21)));
  EXPECT_EQ(f->normals.orientation, NormalOrientation::kPropagate);
  EXPECT_EQ(f->normals.kn, config.normals.kn) << "exact samples are not noisy";
  const EdgeStatistics stats = edge_statistics(f->mesh);
  EXPECT_TRUE(stats.closed()) << stats.boundary_edges << " boundary, " << stats.non_manifold_edges
                              << " non-manifold edges";
  EXPECT_EQ(stats.inconsistent_edges, 0u);
  EXPECT_GT(six_times_volume(f->mesh), 0.0) << "faces wind inward";
  const ObjectErrors err = object_vertex_errors(f->mesh, object);
  std::printf("[ accuracy ] %s: mean %.2e, p95 %.2e of the diagonal (%.4f, %.3f voxel)\n",
              object.name.c_str(), err.mean / object.diagonal(), err.p95 / object.diagonal(),
              err.mean / voxel, err.p95 / voxel);
  EXPECT_LE(err.mean, 0.02 * voxel);
  EXPECT_LE(err.p95, 0.1 * voxel);  // 1e-3 of the diagonal
}

TEST_P(ClosedObjectReconstruction, NoisySamples) {
  // Gaussian noise of 0.2 voxel: the normals stage sees that the plane fits are noisy and fits
  // them again over twice the neighbours.
  const synthetic::ClosedObject object = this->object();
  const ReconstructionConfig config = object_config(object);
  const float voxel = config.voxelize.voxel_size;
  const FramePtr f =
      reconstruct_object(config, points_only(object.sample(100000, 0.2f * voxel, 22)));
  EXPECT_EQ(f->normals.kn, 2 * config.normals.kn);
  EXPECT_TRUE(edge_statistics(f->mesh).closed());
  EXPECT_GT(six_times_volume(f->mesh), 0.0);
  const ObjectErrors err = object_vertex_errors(f->mesh, object);
  std::printf("[ accuracy ] %s, noise 0.2 voxel: mean %.4f voxel\n", object.name.c_str(),
              err.mean / voxel);
  EXPECT_LE(err.mean, 0.1 * voxel);
}

INSTANTIATE_TEST_SUITE_P(Objects, ClosedObjectReconstruction, ::testing::Range(0, 6),
                         [](const ::testing::TestParamInfo<int>& param) {
                           return test::closed_object_test_name(param.param);
                         });

TEST(ObjectReconstruction, SameMeshWithOneAndTwoThreads) {
  const synthetic::ClosedObject object = synthetic::l_shape_object();
  const PointCloud cloud = points_only(object.sample(40000, 0.001f, 23));
  auto mesh = [&](int threads) {
    return test::with_threads(
        threads, [&] { return reconstruct_object(object_config(object), cloud)->mesh; });
  };
  const TriangleMesh one = mesh(1), two = mesh(2);
  EXPECT_GT(one.triangles.size(), 1000u);
  EXPECT_EQ(one.vertices, two.vertices);
  EXPECT_EQ(one.triangles, two.triangles);
}

TEST(ObjectReconstruction, AFileWithNormalsIsMeshedWithoutEstimation) {
  const synthetic::ClosedObject object = synthetic::chamfered_cube_object();
  const PointCloud samples = object.sample(40000, 0.0f, 24);
  const std::string path = test::temp_dir() + "/with_normals.ply";
  TriangleMesh points;
  points.vertices = samples.positions;
  points.normals = samples.normals;
  io::write_ply(path, points);

  const PointCloud cloud = io::read_point_cloud(path);
  ASSERT_TRUE(cloud.has_normals());
  const ReconstructionConfig automatic = object_config(object);
  const FramePtr f = reconstruct_object(automatic, cloud);
  EXPECT_EQ(f->normals.source, NormalSource::kInput);
  EXPECT_EQ(f->normals.estimated, 0u);
  const auto stage = std::find_if(f->timings.begin(), f->timings.end(),
                                  [](const StageRecord& r) { return r.stage == "normals"; });
  ASSERT_NE(stage, f->timings.end());
  EXPECT_EQ(stage->items, 0u) << "the normals stage estimated normals";

  ReconstructionConfig input = automatic;
  input.normals.source = NormalSource::kInput;
  const FramePtr g = reconstruct_object(input, cloud);
  EXPECT_EQ(f->mesh.vertices, g->mesh.vertices);
  EXPECT_EQ(f->mesh.triangles, g->mesh.triangles);
  EXPECT_TRUE(edge_statistics(f->mesh).closed());
  EXPECT_LE(object_vertex_errors(f->mesh, object).mean, 0.02 * automatic.voxelize.voxel_size);
}

TEST(ObjectReconstruction, InwardInputNormalsGiveAnInwardMeshAndEstimationFollowsThem) {
  // The input's normals decide the orientation: all turned inward, the mesh faces inward, both
  // when they are used and when new ones are estimated and signed like them.
  const synthetic::ClosedObject object = synthetic::torus_object();
  PointCloud cloud = object.sample(30000, 0.0f, 25);
  for (Eigen::Vector3f& n : cloud.normals) n = -n;
  ReconstructionConfig config = object_config(object);
  EXPECT_LT(six_times_volume(reconstruct_object(config, cloud)->mesh), 0.0);
  config.normals.source = NormalSource::kEstimate;
  const FramePtr f = reconstruct_object(config, cloud);
  EXPECT_EQ(f->normals.orientation, NormalOrientation::kInput);
  EXPECT_LT(six_times_volume(f->mesh), 0.0);
}

TEST(ObjectReconstruction, PlanarStepsFlattenFacesButNotCurvedSurfaces) {
  // --optimize clean,holes,planes,retriangulate: the torus stays as accurate as its raw
  // extraction (no region of it is planar within a quarter voxel); the chamfered cube's faces
  // are retriangulated from their contours (far fewer triangles).
  for (const synthetic::ClosedObject& object :
       {synthetic::torus_object(), synthetic::chamfered_cube_object()}) {
    SCOPED_TRACE(object.name);
    const PointCloud cloud = points_only(object.sample(60000, 0.0f, 26));
    ReconstructionConfig config = object_config(object);
    const FramePtr raw = reconstruct_object(config, cloud);
    config.optimize.steps = parse_optimize_steps("clean,holes,planes,retriangulate");
    const FramePtr planar = reconstruct_object(config, cloud);
    EXPECT_TRUE(edge_statistics(planar->mesh).closed());
    // Area-sampled: after retriangulation most vertices sit on region borders.
    auto area_error = [&object](const TriangleMesh& mesh) {
      return evaluate_against_truth(
                 mesh, [&object](const Eigen::Vector3f& p) { return object.distance(p); }, 50000)
          .area.mean;
    };
    const double raw_error = area_error(raw->mesh);
    const double planar_error = area_error(planar->mesh);
    std::printf("[ planes ] %s: %zu -> %zu triangles, area-mean error %.2e -> %.2e m\n",
                object.name.c_str(), raw->mesh.triangles.size(), planar->mesh.triangles.size(),
                raw_error, planar_error);
    if (object.name == "torus") {
      EXPECT_LE(planar_error, 1.5 * raw_error);
    } else {
      EXPECT_LT(planar->mesh.triangles.size(), raw->mesh.triangles.size() / 3);
      EXPECT_LE(planar_error, 0.1 * config.voxelize.voxel_size);
    }
  }
}

// Distances (voxels) from points every 0.05 voxel along the object's sharp edges to the mesh
// surface, and from its corners to the nearest mesh vertex.
struct ObjectFeatureErrors {
  DistanceStats edges, corners;
};

ObjectFeatureErrors object_feature_errors(const TriangleMesh& mesh,
                                          const synthetic::ClosedObject& object, float voxel) {
  const MeshDistanceIndex surface(mesh);
  std::vector<float> edges, corners;
  for (const auto& [a, b] : object.feature_edges) {
    const float length = (b - a).norm();
    for (float t = 0.0f; t <= length; t += 0.05f * voxel)
      edges.push_back(surface.closest(a + (b - a) * (t / length)).distance / voxel);
  }
  for (const Eigen::Vector3f& c : object.corners) {
    float nearest = std::numeric_limits<float>::infinity();
    for (const Eigen::Vector3f& v : mesh.vertices) nearest = std::min(nearest, (v - c).norm());
    corners.push_back(nearest / voxel);
  }
  return {distance_stats(edges), distance_stats(corners)};
}

TEST(ObjectReconstruction, ExtendedMarchingCubesKeepsEdgesAndCornersWithoutGivenNormals) {
  // CAD-like parts sampled without normals: --extract emc estimates feature-preserving normals
  // and puts the box's, the L's and the chamfer's edges on the mesh where marching cubes rounds
  // them off by a third of a voxel and more.
  for (const synthetic::ClosedObject& object :
       {synthetic::box_object(), synthetic::l_shape_object(), synthetic::chamfered_cube_object()}) {
    SCOPED_TRACE(object.name);
    const PointCloud cloud = points_only(object.sample(100000, 0.0f, 27));
    ReconstructionConfig config = object_config(object);
    const float voxel = config.voxelize.voxel_size;
    config.extract.method = ExtractMethod::kMarchingCubes;
    const FramePtr mc = reconstruct_object(config, cloud);
    config.extract.method = ExtractMethod::kExtendedMarchingCubes;
    const FramePtr emc = reconstruct_object(config, cloud);
    EXPECT_TRUE(edge_statistics(emc->mesh).closed());
    const ObjectFeatureErrors mc_features = object_feature_errors(mc->mesh, object, voxel);
    const ObjectFeatureErrors emc_features = object_feature_errors(emc->mesh, object, voxel);
    const ObjectErrors mc_error = object_vertex_errors(mc->mesh, object);
    const ObjectErrors emc_error = object_vertex_errors(emc->mesh, object);
    std::printf(
        "[ emc ] %s: edges p95 %.3f voxel (mc %.3f), corners mean %.3f max %.3f (mc %.3f), "
        "vertex p95 %.4f voxel (mc %.4f)\n",
        object.name.c_str(), emc_features.edges.p95, mc_features.edges.p95,
        emc_features.corners.mean, emc_features.corners.max, mc_features.corners.mean,
        emc_error.p95 / voxel, mc_error.p95 / voxel);
    EXPECT_LT(emc_features.edges.p95, 0.05);
    EXPECT_GT(mc_features.edges.p95, 0.3);
    EXPECT_LT(emc_features.corners.mean, 0.1);
    EXPECT_GT(mc_features.corners.mean, 0.4);
    EXPECT_LE(emc_error.p95, 0.8 * mc_error.p95);
  }
}

// Issue 55: exact samples with their exact normals (a CAD export) get the same automatic
// extended marching cubes as the same samples without normals, not marching cubes (which was
// 6.7x less accurate on a machined part); the normals are used as they are.
TEST(ObjectReconstruction, ExactNormalsGetExtendedMarchingCubesLikeEstimatedOnes) {
  for (const synthetic::ClosedObject& object :
       {synthetic::chamfered_cube_object(), synthetic::l_shape_object()}) {
    SCOPED_TRACE(object.name);
    const PointCloud with_normals = object.sample(100000, 0.0f, 31);
    const ReconstructionConfig config = object_config(object);
    const FramePtr given = reconstruct_object(config, with_normals);
    const FramePtr estimated = reconstruct_object(config, points_only(with_normals));
    EXPECT_EQ(given->normals.source, NormalSource::kInput);
    EXPECT_EQ(given->normals.estimated, 0u);
    EXPECT_TRUE(given->normals.sharp);
    EXPECT_TRUE(estimated->normals.sharp);
    const ObjectErrors given_error = object_vertex_errors(given->mesh, object);
    const ObjectErrors estimated_error = object_vertex_errors(estimated->mesh, object);
    std::printf(
        "[ exact normals ] %s: mean %.3g (estimated %.3g), p95 %.3g (%.3g) of the diagonal\n",
        object.name.c_str(), given_error.mean / object.diagonal(),
        estimated_error.mean / object.diagonal(), given_error.p95 / object.diagonal(),
        estimated_error.p95 / object.diagonal());
    EXPECT_LE(given_error.mean, 1.5 * estimated_error.mean);
    EXPECT_TRUE(edge_statistics(given->mesh).closed());
  }
  // Noisy samples with normals stay with marching cubes.
  const synthetic::ClosedObject box = synthetic::box_object();
  const FramePtr noisy =
      reconstruct_object(object_config(box), box.sample(100000, 0.002f * box.diagonal(), 32));
  EXPECT_FALSE(noisy->normals.sharp);
}

TEST(ObjectReconstruction, PointsOnALineAreAClearErrorNotARibbon) {
  PointCloud line;
  for (int i = 0; i < 300; ++i) line.positions.emplace_back(0.01f * i, 0.5f * 0.01f * i, 0.0f);
  const FramePtr f = ReconstructionPipeline(ReconstructionConfig{}).reconstruct(line, "line");
  ASSERT_FALSE(f->ok());
  EXPECT_NE(f->error.find("lie on a line"), std::string::npos) << f->error;
  EXPECT_EQ(f->failed_stage, "filter");
}

TEST(ObjectReconstruction, BunnyNormalsAreConsistentAndFaceTheScanner) {
  MESHFLOW_REQUIRE_DATA("objects/bunny.pcd");
  const PointCloud cloud = io::read_point_cloud(test::data_path("objects/bunny.pcd"));
  const FramePtr f = reconstruct_object(ReconstructionConfig{}, cloud);
  EXPECT_EQ(f->normals.orientation, NormalOrientation::kPropagate);
  // One view of the bunny, scanned from +z: the normals face that side...
  Eigen::Vector3f mean = Eigen::Vector3f::Zero();
  for (const Eigen::Vector3f& n : f->cloud.normals) mean += n;
  EXPECT_GT(mean.normalized().z(), 0.5f);
  // ...and agree with the outward side of the mesh made from them at every point: the nearest
  // vertex's normal (the mesh's own winding) is within 90 degrees.
  ASSERT_EQ(f->mesh.normals.size(), f->mesh.vertices.size());
  std::size_t agree = 0;
  for (std::size_t i = 0; i < f->cloud.size(); ++i) {
    std::size_t nearest = 0;
    for (std::size_t v = 1; v < f->mesh.vertices.size(); ++v)
      if ((f->mesh.vertices[v] - f->cloud.positions[i]).squaredNorm() <
          (f->mesh.vertices[nearest] - f->cloud.positions[i]).squaredNorm())
        nearest = v;
    agree += f->mesh.normals[nearest].dot(f->cloud.normals[i]) > 0.0f ? 1 : 0;
  }
  EXPECT_GE(static_cast<double>(agree), 0.999 * static_cast<double>(f->cloud.size()))
      << agree << " of " << f->cloud.size();
}

TEST(ObjectReconstruction, BunnyRimStaysWithinAVoxelOfTheData) {
  // One view: an open surface whose rim the distance band would carry up to two voxels past
  // the last points (32 mm at 18 mm voxels); peeling the rim keeps every vertex within one.
  MESHFLOW_REQUIRE_DATA("objects/bunny.pcd");
  const PointCloud cloud = io::read_point_cloud(test::data_path("objects/bunny.pcd"));
  const FramePtr f = reconstruct_object(ReconstructionConfig{}, cloud);
  ASSERT_TRUE(f->ok()) << f->error;
  EXPECT_GT(f->rim_trimmed, 0u);
  const KdTreeIndex points(f->cloud.positions);
  float farthest = 0.0f;
  for (const Eigen::Vector3f& v : f->mesh.vertices) {
    std::uint32_t nearest = 0;
    float d2 = 0.0f;
    points.knn(v, 1, &nearest, &d2);
    farthest = std::max(farthest, std::sqrt(d2));
  }
  std::printf("[ bunny ] rim: %zu triangles peeled, farthest vertex %.1f mm (voxel %.1f mm)\n",
              f->rim_trimmed, 1e3 * farthest, 1e3 * f->voxel_size);
  EXPECT_LE(farthest, f->voxel_size);
}

}  // namespace
}  // namespace meshflow
