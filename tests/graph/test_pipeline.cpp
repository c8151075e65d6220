#include "graph/pipeline.h"

#include <gtest/gtest.h>

#include <chrono>
#include <random>
#include <thread>

#include "graph/stages.h"
#include "nodes/extract/extract_surface.h"
#include "nodes/synthetic/shapes.h"
#include "runtime/error.h"

namespace meshflow {
namespace {

ReconstructionConfig sphere_config() {
  ReconstructionConfig c;
  c.voxelize.voxel_size = 0.1f;
  c.normals.orientation = NormalOrientation::kAwayFromViewpoint;
  return c;
}

TEST(Pipeline, ManyFramesInFlightArriveInOrderAndFailuresFlowThrough) {
  ReconstructionPipeline pipeline(sphere_config(), 4);
  const int frames = 12;
  int produced = 0;
  std::vector<FramePtr> out;
  std::mt19937 rng(3);
  pipeline.run(
      [&]() -> FramePtr {
        if (produced == frames) return nullptr;
        auto f = std::make_shared<Frame>();
        const int i = produced++;
        f->name = "frame" + std::to_string(i);
        const int delay_ms = static_cast<int>(rng() % 15);
        f->load = [i, delay_ms] {
          std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));  // random stage delays
          if (i == 5) throw Error("frame5.ply", "line 3", "unreadable");
          return synthetic::sample_surface(synthetic::Sphere{{0, 0, 0}, 1.0f + 0.05f * i}, 0.05f,
                                           0.0f, 1);
        };
        return f;
      },
      [&](const FramePtr& f) { out.push_back(f); });
  ASSERT_EQ(out.size(), static_cast<std::size_t>(frames));
  for (int i = 0; i < frames; ++i) {
    EXPECT_EQ(out[static_cast<std::size_t>(i)]->seq, static_cast<std::uint64_t>(i));
    EXPECT_EQ(out[static_cast<std::size_t>(i)]->name, "frame" + std::to_string(i));
    if (i == 5) {
      EXPECT_FALSE(out[5]->ok());
      EXPECT_EQ(out[5]->failed_stage, "read");
      EXPECT_NE(out[5]->error.find("frame5.ply: line 3: unreadable"), std::string::npos);
      EXPECT_EQ(out[5]->timings.size(), 1u) << "later stages skip a failed frame";
    } else {
      EXPECT_TRUE(out[static_cast<std::size_t>(i)]->ok())
          << out[static_cast<std::size_t>(i)]->error;
      EXPECT_GT(out[static_cast<std::size_t>(i)]->mesh.triangles.size(), 100u);
      EXPECT_EQ(out[static_cast<std::size_t>(i)]->timings.size(), 8u);
    }
  }
}

// Many quick frames (every other one failing at once) with many in flight, again and again:
// they reach the sink in input order every time (see detail::InOrderNode).
TEST(Pipeline, ManyQuickFramesArriveInInputOrderEveryRun) {
  ReconstructionPipeline pipeline(sphere_config(), 8);
  const std::size_t frames = 96;
  for (int run = 0; run < 10; ++run) {
    std::size_t produced = 0;
    std::vector<std::size_t> order;
    pipeline.run(
        [&]() -> FramePtr {
          if (produced == frames) return nullptr;
          auto f = std::make_shared<Frame>();
          f->source_index = produced++;
          const bool fails = f->source_index % 2 == 1;
          f->load = [fails] {
            if (fails) throw Error("quick.ply", "line 1", "unreadable");
            return synthetic::sample_surface(synthetic::Sphere{{0, 0, 0}, 1.0f}, 0.3f, 0.0f, 1);
          };
          return f;
        },
        [&](const FramePtr& f) { order.push_back(f->source_index); });
    ASSERT_EQ(order.size(), frames);
    for (std::size_t i = 0; i < frames; ++i) ASSERT_EQ(order[i], i) << "run " << run;
  }
}

TEST(Pipeline, EmptyOrAllNaNCloudFailsInTheFilterStage) {
  ReconstructionPipeline pipeline(sphere_config());
  PointCloud nan_cloud;
  nan_cloud.positions.assign(10, Eigen::Vector3f::Constant(std::nanf("")));
  const FramePtr f = pipeline.reconstruct(nan_cloud, "nan.xyz");
  EXPECT_FALSE(f->ok());
  EXPECT_EQ(f->failed_stage, "filter");
  EXPECT_NE(f->error.find("10 NaN/Inf"), std::string::npos) << f->error;
  EXPECT_FALSE(pipeline.reconstruct(PointCloud{}, "empty")->ok());
}

TEST(Pipeline, CoincidentPointsFailWithAReasonWhateverTheVoxelSize) {
  for (float voxel : {0.0f, 0.05f}) {  // 0: chosen from the points
    ReconstructionConfig config;
    config.voxelize.voxel_size = voxel;
    ReconstructionPipeline pipeline(config);
    PointCloud same;
    same.positions.assign(100, Eigen::Vector3f(0.5f, 0.5f, 0.5f));
    const FramePtr f = pipeline.reconstruct(same, "same.xyz");
    EXPECT_FALSE(f->ok());
    EXPECT_EQ(f->failed_stage, "filter");
    EXPECT_NE(f->error.find("coincide"), std::string::npos) << f->error;
  }
}

// Three points span a plane but make no surface: the frame fails in a stage, saying so, instead
// of passing as an "ok" frame with an empty mesh (the CLI's run, the embedding API and Python
// all go through these stages).
TEST(Pipeline, ThreePointsFailAStageInsteadOfGivingAnEmptyMesh) {
  for (float voxel : {0.0f, 0.05f}) {  // 0: chosen from the points
    ReconstructionConfig config;
    config.voxelize.voxel_size = voxel;
    ReconstructionPipeline pipeline(config);
    PointCloud three;
    three.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    const FramePtr f = pipeline.reconstruct(three, "three.xyz");
    ASSERT_FALSE(f->ok()) << "voxel " << voxel << ": " << f->mesh.triangles.size() << " triangles";
    EXPECT_TRUE(f->failed_stage == "extract" || f->failed_stage == "optimize") << f->failed_stage;
    EXPECT_NE(f->error.find("three.xyz: " + f->failed_stage + ": "), std::string::npos) << f->error;
    EXPECT_NE(f->error.find("triangle"), std::string::npos) << f->error;
  }
}

// Optimisation that removes every triangle fails the frame too, naming the step.
TEST(Pipeline, AnOptimizeStepThatRemovesEveryTriangleFailsTheFrame) {
  ReconstructionConfig config = sphere_config();
  config.optimize.cleanup.min_component_triangles = 1000000;  // larger than the sphere's mesh
  ReconstructionPipeline pipeline(config);
  const FramePtr f = pipeline.reconstruct(
      synthetic::sample_surface(synthetic::Sphere{{0, 0, 0}, 1.0f}, 0.05f, 0.0f, 1), "sphere");
  ASSERT_FALSE(f->ok()) << f->mesh.triangles.size() << " triangles";
  EXPECT_EQ(f->failed_stage, "optimize");
  EXPECT_NE(f->error.find("the clean step removed all"), std::string::npos) << f->error;
  EXPECT_NE(f->error.find("--min-component 1000000"), std::string::npos) << f->error;
}

TEST(Pipeline, StagesRecordTimingsAndItems) {
  Frame f;
  f.cloud = synthetic::sample_surface(synthetic::Sphere{}, 0.05f, 0.0f, 1);
  const ReconstructionConfig c = sphere_config();
  stages::run_stage("filter", stages::filter, f, c);
  stages::run_stage("index", stages::index, f, c);
  stages::run_stage("normals", stages::normals, f, c);
  ASSERT_EQ(f.timings.size(), 3u);
  EXPECT_EQ(f.timings[2].items, f.cloud.size());
  EXPECT_GE(f.timings[2].end_s, f.timings[2].start_s);
  EXPECT_EQ(f.cloud.normals.size(), f.cloud.size());
}

// After "extract" the frame keeps what the reports count (the grid's cells and corners, the valid
// samples) and the mesh, not what only extraction reads: the cell corners, the distance values
// and the spatial index are released (the whole cloud's peak memory), the mesh unchanged.
TEST(Pipeline, ExtractReleasesTheFieldAndTheIndexAndKeepsTheCounts) {
  for (const ExtractMethod method :
       {ExtractMethod::kMarchingCubes, ExtractMethod::kExtendedMarchingCubes}) {
    Frame f;
    f.cloud = synthetic::sample_surface(synthetic::Sphere{}, 0.05f, 0.0f, 1);
    ReconstructionConfig c = sphere_config();
    c.extract.method = method;
    c.max_rim_voxels = 0.0f;  // the stage's mesh is then extract_surface()'s
    for (const stages::NamedStage& stage :
         {stages::NamedStage{"filter", stages::filter}, stages::NamedStage{"index", stages::index},
          stages::NamedStage{"normals", stages::normals},
          stages::NamedStage{"voxelize", stages::voxelize},
          stages::NamedStage{"distance", stages::distance}})
      stages::run_stage(stage.name, stage.body, f, c);
    ASSERT_TRUE(f.ok()) << f.error;
    const SparseGrid grid = f.grid;
    const DistanceField field = f.distance;
    const TriangleMesh expected = extract_surface(grid, field, f.cloud, f.index.get(), c.extract);
    ASSERT_FALSE(expected.triangles.empty());
    stages::run_stage("extract", stages::extract, f, c);
    ASSERT_TRUE(f.ok()) << f.error;
    EXPECT_EQ(f.mesh.vertices, expected.vertices);
    EXPECT_EQ(f.mesh.triangles, expected.triangles);
    EXPECT_EQ(f.index, nullptr);
    EXPECT_TRUE(f.grid.cell_corners.empty());
    EXPECT_TRUE(f.distance.values.empty());
    EXPECT_EQ(f.grid.cells, grid.cells);
    EXPECT_EQ(f.grid.corners, grid.corners);
    EXPECT_EQ(f.distance.valid_count(), field.valid_count());
    EXPECT_GT(field.valid_count(), 0u);
  }
}

}  // namespace
}  // namespace meshflow
