// The depth-frame path through the graph: synthetic ground truth and the real Redwood frames.

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "graph/fusion_pipeline.h"
#include "graph/sequence_runner.h"
#include "nodes/normals/organized_normals.h"
#include "nodes/synthetic/depth_sequence.h"
#include "nodes/triangulate/depth_triangulation.h"
#include "runtime/threads.h"
#include "test_support.h"

namespace meshflow {
namespace {

synthetic::DepthSequenceConfig small_camera(int frames) {
  synthetic::DepthSequenceConfig c;
  c.frames = frames;
  c.intrinsics = PinholeIntrinsics{160, 120, 131.25f, 131.25f, 79.5f, 59.5f};
  return c;
}

// A real frame came through: a mesh with between `low` and `high` triangles, finite vertices,
// every edge manifold and consistently oriented.
void expect_sound_mesh(const Frame& f, std::size_t low, std::size_t high) {
  ASSERT_TRUE(f.ok()) << f.error;
  EXPECT_GT(f.mesh.triangles.size(), low);
  EXPECT_LT(f.mesh.triangles.size(), high);
  for (const auto& v : f.mesh.vertices) ASSERT_TRUE(v.allFinite());
  const EdgeStatistics s = edge_statistics(f.mesh);
  EXPECT_EQ(s.non_manifold_edges, 0u);
  EXPECT_EQ(s.inconsistent_edges, 0u);
}

TEST(DepthPath, SyntheticDepthFramesWithinAQuarterVoxel) {
  const float voxel = 0.04f;
  const synthetic::Scene scene = synthetic::demo_room_scene();
  const auto seq = synthetic::make_depth_sequence(scene, small_camera(4));
  ReconstructionConfig config;
  config.voxelize.voxel_size = voxel;
  ReconstructionPipeline pipeline(config, 2);
  const SequenceRunStats stats = run_sequence(pipeline, *seq, {}, [&](const Frame& f) {
    ASSERT_TRUE(f.ok()) << f.error;
    EXPECT_EQ(f.kind, FrameKind::kDepthImage);
    ASSERT_TRUE(f.depth.has_value());
    EXPECT_GT(f.depth->counts.valid, 10000u);
    EXPECT_TRUE(f.depth->image.depth.empty()) << "the image is released once meshed";
    const auto err = test::vertex_errors(
        f.mesh, [&](const Eigen::Vector3f& p) { return synthetic::surface_distance(scene, p); });
    std::printf("[ accuracy ] depth frame %zu: mean %.4f voxel, %zu triangles\n", f.source_index,
                err.mean / voxel, f.mesh.triangles.size());
    EXPECT_LT(err.mean / voxel, 0.25);
    EXPECT_EQ(edge_statistics(f.mesh).non_manifold_edges, 0u);
  });
  EXPECT_EQ(stats.frames_ok, 4u);
}

TEST(DepthPath, SameMeshesWithOneAndTwoThreads) {
  const auto seq = synthetic::make_depth_sequence(synthetic::demo_room_scene(), small_camera(2));
  auto meshes = [&](int threads) {
    ThreadLimit limit(threads);
    ReconstructionConfig config;
    config.voxelize.voxel_size = 0.04f;
    ReconstructionPipeline pipeline(config, 2);
    std::vector<TriangleMesh> out;
    run_sequence(pipeline, *seq, {}, [&](const Frame& f) { out.push_back(f.mesh); });
    return out;
  };
  const auto one = meshes(1), two = meshes(2);
  ASSERT_EQ(one.size(), 2u);
  for (std::size_t i = 0; i < one.size(); ++i) {
    EXPECT_GT(one[i].triangles.size(), 100u);
    EXPECT_EQ(one[i].vertices, two[i].vertices);
    EXPECT_EQ(one[i].triangles, two[i].triangles);
  }
}

TEST(DepthPath, AllInvalidDepthFailsThatFrameOnly) {
  class Blank final : public io::Sequence {
   public:
    std::size_t size() const override { return 1; }
    io::SequenceFrame frame(std::size_t) const override {
      io::SequenceFrame f;
      f.name = "blank.png";
      f.load_depth = [] {
        DepthFrame d;
        d.depth = Image::filled<std::uint16_t>(48, 64, 0);
        d.intrinsics = PinholeIntrinsics{64, 48, 50, 50, 31.5f, 23.5f};
        return d;
      };
      return f;
    }
    std::string description() const override { return "blank"; }
  } blank;
  ReconstructionPipeline pipeline(ReconstructionConfig{}, 1);
  const SequenceRunStats stats = run_sequence(pipeline, blank, {}, [](const Frame& f) {
    EXPECT_EQ(f.failed_stage, "filter");
    EXPECT_NE(f.error.find("no valid depth pixel"), std::string::npos) << f.error;
  });
  EXPECT_EQ(stats.frames_failed, 1u);
}

// Per-frame triangulation instead of the volumetric stages: the graph's mesh of every frame is
// exactly what the kernel makes of it, and the stages are read and triangulate.
TEST(DepthPath, TriangulatedPerFrameThroughThePipeline) {
  const auto seq = synthetic::make_depth_sequence(synthetic::demo_room_scene(), small_camera(3));
  ReconstructionConfig config;
  config.triangulation.method = DepthTriangulationMethod::kRestrictedQuadtree;
  config.triangulation.decimate_to = 0.5f;
  ReconstructionPipeline pipeline(config, 2, /*triangulate_depth_maps=*/true);
  const SequenceRunStats stats = run_sequence(pipeline, *seq, {}, [&](const Frame& f) {
    ASSERT_TRUE(f.ok()) << f.error;
    const TriangleMesh direct =
        triangulate_depth(seq->frame(f.source_index).load_depth(), config.triangulation);
    EXPECT_GT(direct.triangles.size(), 1000u);
    EXPECT_EQ(f.mesh.vertices, direct.vertices);
    EXPECT_EQ(f.mesh.triangles, direct.triangles);
    ASSERT_EQ(f.timings.size(), 2u);
    EXPECT_EQ(f.timings[0].stage, "read");
    EXPECT_EQ(f.timings[1].stage, "triangulate");
  });
  EXPECT_EQ(stats.frames_ok, 3u);
}

// An organized cloud (a depth frame back-projected, NaN where invalid) is triangulated as its
// pixel grid; an unorganized cloud fails its frame with a message saying what was expected.
TEST(DepthPath, OrganizedCloudsTriangulatePerFrameUnorganizedOnesFail) {
  const auto seq = synthetic::make_depth_sequence(synthetic::demo_room_scene(), small_camera(1));
  const DepthFrame depth = seq->frame(0).load_depth();
  const PointCloud organized = back_project(depth, depth_in_metres(depth));
  ASSERT_TRUE(organized.is_organized());
  ReconstructionConfig config;
  config.triangulation.method = DepthTriangulationMethod::kRestrictedQuadtree;
  ReconstructionPipeline pipeline(config, 1, /*triangulate_depth_maps=*/true);
  const FramePtr ok = pipeline.reconstruct(organized, "organized");
  ASSERT_TRUE(ok->ok()) << ok->error;
  const TriangleMesh direct = triangulate_organized(organized, config.triangulation);
  EXPECT_GT(direct.triangles.size(), 1000u);
  EXPECT_EQ(ok->mesh.triangles, direct.triangles);
  EXPECT_EQ(ok->mesh.vertices, direct.vertices);

  PointCloud unorganized = organized;
  unorganized.width = static_cast<std::uint32_t>(unorganized.size());
  unorganized.height = 1;
  const FramePtr failed = pipeline.reconstruct(unorganized, "scan.ply");
  EXPECT_FALSE(failed->ok());
  EXPECT_EQ(failed->failed_stage, "triangulate");
  EXPECT_NE(failed->error.find("scan.ply"), std::string::npos) << failed->error;
  EXPECT_NE(failed->error.find("organized point cloud"), std::string::npos) << failed->error;
}

// The stage names a frame's timings record, in order.
std::vector<std::string> visited_stages(const Frame& f) {
  std::vector<std::string> names;
  names.reserve(f.timings.size());
  for (const StageRecord& r : f.timings) names.push_back(r.stage);
  return names;
}

// With organized_as_depth a pinhole cloud takes the depth path (image normals, projective
// distance) and meshes as accurately as the depth frame it came from; without, the cloud path.
// The graph routes each frame by its kind after "read": a depth frame never enters the kd-tree
// and normals stages a cloud needs, and a frame that failed enters no stage after its failure.
TEST(DepthPath, OrganizedCloudsTakeTheDepthPathWhenAsked) {
  const synthetic::Scene scene = synthetic::demo_room_scene();
  const DepthFrame camera =
      synthetic::make_depth_sequence(scene, small_camera(1))->frame(0).load_depth();
  const PointCloud cloud = test::camera_frame_cloud(camera);
  ReconstructionConfig config;
  config.voxelize.voxel_size = 0.04f;
  config.organized_as_depth = true;
  const FramePtr depth_path = ReconstructionPipeline(config, 1).reconstruct(cloud);
  ASSERT_TRUE(depth_path->ok()) << depth_path->error;
  EXPECT_EQ(depth_path->kind, FrameKind::kDepthImage);
  EXPECT_EQ(
      visited_stages(*depth_path),
      (std::vector<std::string>{"read", "filter", "voxelize", "distance", "extract", "optimize"}));
  TriangleMesh mesh = depth_path->mesh;
  for (Eigen::Vector3f& v : mesh.vertices) v = camera.T_world_camera * v;
  const auto err = test::vertex_errors(
      mesh, [&](const Eigen::Vector3f& p) { return synthetic::surface_distance(scene, p); });
  EXPECT_GT(mesh.triangles.size(), 1000u);
  EXPECT_LT(err.mean / 0.04, 0.25);

  config.organized_as_depth = false;
  const FramePtr cloud_path = ReconstructionPipeline(config, 1).reconstruct(cloud);
  ASSERT_TRUE(cloud_path->ok()) << cloud_path->error;
  EXPECT_EQ(cloud_path->kind, FrameKind::kCloud);
  EXPECT_FALSE(cloud_path->depth.has_value());
  EXPECT_GT(cloud_path->mesh.triangles.size(), 1000u);
  EXPECT_EQ(visited_stages(*cloud_path),
            (std::vector<std::string>{"read", "filter", "index", "normals", "voxelize", "distance",
                                      "extract", "optimize"}));

  config.compression = MeshCompression::kEdgebreaker;
  config.organized_as_depth = true;
  const FramePtr compressed = ReconstructionPipeline(config, 1).reconstruct(cloud);
  ASSERT_TRUE(compressed->ok()) << compressed->error;
  EXPECT_FALSE(compressed->compressed.empty());
  EXPECT_EQ(visited_stages(*compressed).back(), "compress");

  PointCloud nothing_valid = cloud;
  for (Eigen::Vector3f& p : nothing_valid.positions) p.setConstant(std::nanf(""));
  config.organized_as_depth = false;
  const FramePtr failed = ReconstructionPipeline(config, 1).reconstruct(nothing_valid);
  EXPECT_FALSE(failed->ok());
  EXPECT_EQ(failed->failed_stage, "filter");
  EXPECT_EQ(visited_stages(*failed), (std::vector<std::string>{"read", "filter"}));
}

TEST(DepthPath, RealKinectPcdFramesFuseIntoOneMap) {
  MESHFLOW_REQUIRE_DATA("kinect_pcl/grabber_sequences/pcd");
  const auto seq = io::open_sequence(test::data_path("kinect_pcl/grabber_sequences/pcd"));
  FusionConfig config;
  config.tsdf.voxel_size = 0.01f;
  FusionPipeline pipeline(config, 2);
  const SequenceRunStats stats =
      run_sequence(pipeline, *seq, {}, [](const Frame& f) { ASSERT_TRUE(f.ok()) << f.error; });
  EXPECT_EQ(stats.frames_ok, 3u);
  const TriangleMesh mesh = pipeline.extract_mesh();
  std::printf("[ kinect ] 3 PCD frames fused at 1 cm: %zu triangles\n", mesh.triangles.size());
  EXPECT_GT(mesh.triangles.size(), 20000u);
  EXPECT_EQ(edge_statistics(mesh).non_manifold_edges, 0u);
}

TEST(DepthPath, RealKinectPcdFramesTriangulatedPerFrame) {
  MESHFLOW_REQUIRE_DATA("kinect_pcl/grabber_sequences/pcd");
  const auto seq = io::open_sequence(test::data_path("kinect_pcl/grabber_sequences/pcd"));
  ReconstructionConfig config;
  config.triangulation.method = DepthTriangulationMethod::kRestrictedQuadtree;
  config.triangulation.decimate_to = 0.25f;
  ReconstructionPipeline pipeline(config, 2, /*triangulate_depth_maps=*/true);
  const SequenceRunStats stats = run_sequence(pipeline, *seq, {}, [&](const Frame& f) {
    std::printf("[ kinect ] %s: %zu triangles\n", f.name.c_str(), f.mesh.triangles.size());
    expect_sound_mesh(f, 5000, 30000);
  });
  EXPECT_EQ(stats.frames_ok, 3u);
}

TEST(DepthPath, RealRedwoodFramesPerFrameAt1cm) {
  MESHFLOW_REQUIRE_DATA("rgbd_redwood/trajectory.log");
  const auto seq = io::open_sequence(test::data_path("rgbd_redwood"));
  ReconstructionConfig config;
  config.voxelize.voxel_size = 0.01f;
  ReconstructionPipeline pipeline(config, 2);
  const SequenceRunStats stats = run_sequence(
      pipeline, *seq, {}, [&](const Frame& f) { expect_sound_mesh(f, 100000, 2000000); });
  EXPECT_EQ(stats.frames_ok, 5u);
}

TEST(DepthPath, RealKinectTiffFramesPerFrame) {
  MESHFLOW_REQUIRE_DATA("kinect_pcl/grabber_sequences/tiff");
  const auto seq = io::open_sequence(test::data_path("kinect_pcl/grabber_sequences/tiff"));
  ReconstructionConfig config;
  config.voxelize.voxel_size = 0.01f;
  ReconstructionPipeline pipeline(config, 2);
  const SequenceRunStats stats = run_sequence(pipeline, *seq, {}, [&](const Frame& f) {
    ASSERT_TRUE(f.ok()) << f.error;
    EXPECT_GT(f.mesh.triangles.size(), 20000u);
    EXPECT_LT(f.mesh.triangles.size(), 500000u);
    EXPECT_EQ(edge_statistics(f.mesh).non_manifold_edges, 0u);
  });
  EXPECT_EQ(stats.frames_ok, 3u);
}

}  // namespace
}  // namespace meshflow
