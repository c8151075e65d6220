// Accuracy against analytic ground truth, through the whole pipeline (normals estimated, not
// given). Voxel size h; samples about h/4 apart; noise, where added, is Gaussian of 0.2 h.

#include <gtest/gtest.h>

#include <cstdio>

#include "graph/pipeline.h"
#include "nodes/synthetic/shapes.h"
#include "runtime/threads.h"
#include "test_support.h"

namespace meshflow {
namespace {

constexpr float kAccuracyVoxel = 0.05f;

ReconstructionConfig closed_shape_config(const Eigen::Vector3f& centre) {
  ReconstructionConfig c;
  c.voxelize.voxel_size = kAccuracyVoxel;
  c.normals.orientation = NormalOrientation::kAwayFromViewpoint;
  c.normals.viewpoint = centre;
  return c;
}

// Prints and records the measured error so test logs carry the numbers.
void report(const char* shape, const test::ErrorStats& err) {
  std::printf("[ accuracy ] %s: mean %.4f voxel, max %.3f voxel\n", shape,
              err.mean / kAccuracyVoxel, err.max / kAccuracyVoxel);
  ::testing::Test::RecordProperty("mean_error_voxels", std::to_string(err.mean / kAccuracyVoxel));
}

FramePtr reconstruct(const ReconstructionConfig& config, PointCloud cloud) {
  FramePtr f = ReconstructionPipeline(config).reconstruct(std::move(cloud));
  EXPECT_TRUE(f->ok()) << f->error;
  EXPECT_GT(f->mesh.triangles.size(), 100u);
  return f;
}

struct Case {
  float noise_voxels;
  double max_mean_voxels;
};

void PrintTo(const Case& c, std::ostream* os) {
  *os << "noise " << c.noise_voxels << " voxel, mean error bound " << c.max_mean_voxels << " voxel";
}

class Accuracy : public ::testing::TestWithParam<Case> {};

TEST_P(Accuracy, Sphere) {
  const synthetic::Sphere sphere{{0.01f, 0.02f, -0.03f}, 1.0f};
  const auto cloud = synthetic::sample_surface(sphere, kAccuracyVoxel / 4,
                                               GetParam().noise_voxels * kAccuracyVoxel, 1);
  const FramePtr f = reconstruct(closed_shape_config(sphere.center), cloud);
  const auto err = test::vertex_errors(
      f->mesh, [&](const Eigen::Vector3f& p) { return synthetic::surface_distance(sphere, p); });
  report("sphere", err);
  EXPECT_LT(err.mean / kAccuracyVoxel, GetParam().max_mean_voxels);
  const EdgeStatistics stats = edge_statistics(f->mesh);
  EXPECT_TRUE(stats.closed()) << stats.boundary_edges << " boundary, " << stats.non_manifold_edges
                              << " non-manifold";
  EXPECT_EQ(stats.inconsistent_edges, 0u);
  std::size_t outward = 0;
  for (const Triangle& t : f->mesh.triangles) {
    const Eigen::Vector3f c =
        (f->mesh.vertices[t[0]] + f->mesh.vertices[t[1]] + f->mesh.vertices[t[2]]) / 3.0f;
    outward += face_normal(f->mesh, t).dot((c - sphere.center).normalized()) > 0.0f ? 1 : 0;
  }
  EXPECT_EQ(outward, f->mesh.triangles.size());
}

TEST_P(Accuracy, Box) {
  const synthetic::Box box{{0.02f, -0.01f, 0.03f}, {0.6f, 0.45f, 0.3f}};
  const auto cloud = synthetic::sample_surface(box, kAccuracyVoxel / 4,
                                               GetParam().noise_voxels * kAccuracyVoxel, 2);
  const FramePtr f = reconstruct(closed_shape_config(box.center), cloud);
  const auto err = test::vertex_errors(
      f->mesh, [&](const Eigen::Vector3f& p) { return synthetic::surface_distance(box, p); });
  report("box", err);
  EXPECT_LT(err.mean / kAccuracyVoxel, GetParam().max_mean_voxels);
  EXPECT_EQ(edge_statistics(f->mesh).non_manifold_edges, 0u);
}

TEST_P(Accuracy, PlaneWithStep) {
  const synthetic::StepPlane step{1.0f, 0.25f};
  const auto cloud = synthetic::sample_surface(step, kAccuracyVoxel / 4,
                                               GetParam().noise_voxels * kAccuracyVoxel, 3);
  ReconstructionConfig config;
  config.voxelize.voxel_size = kAccuracyVoxel;
  config.normals.orientation = NormalOrientation::kTowardViewpoint;
  // The sensor sees the wall from the low side, so all normals agree in orientation.
  config.normals.viewpoint = Eigen::Vector3f(-1.0f, 0.1f, 3.0f);
  const FramePtr f = reconstruct(config, cloud);
  const auto err = test::vertex_errors(
      f->mesh, [&](const Eigen::Vector3f& p) { return synthetic::surface_distance(step, p); });
  report("plane with step", err);
  EXPECT_LT(err.mean / kAccuracyVoxel, GetParam().max_mean_voxels);
  EXPECT_EQ(edge_statistics(f->mesh).non_manifold_edges, 0u);
}

INSTANTIATE_TEST_SUITE_P(Reconstruction, Accuracy,
                         ::testing::Values(Case{0.0f, 0.1}, Case{0.2f, 0.25}),
                         [](const ::testing::TestParamInfo<Case>& param_info) {
                           return param_info.param.noise_voxels == 0.0f ? std::string("Exact")
                                                                        : std::string("Noisy");
                         });

TEST(Reconstruction, SameMeshVertexForVertexWithOneAndTwoThreads) {
  const synthetic::Box box{{0, 0, 0}, {0.5f, 0.4f, 0.3f}};
  const auto cloud = synthetic::sample_surface(box, kAccuracyVoxel / 3, 0.2f * kAccuracyVoxel, 4);
  TriangleMesh one, two;
  {
    ThreadLimit limit(1);
    one = reconstruct(closed_shape_config(box.center), cloud)->mesh;
  }
  {
    ThreadLimit limit(2);
    two = reconstruct(closed_shape_config(box.center), cloud)->mesh;
  }
  EXPECT_GT(one.triangles.size(), 500u);
  EXPECT_EQ(one.vertices, two.vertices);
  EXPECT_EQ(one.triangles, two.triangles);
  EXPECT_EQ(one.normals, two.normals);
}

}  // namespace
}  // namespace meshflow
