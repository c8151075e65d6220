#include "graph/sequence_runner.h"

#include <gtest/gtest.h>

#include "nodes/synthetic/scan_sequence.h"
#include "runtime/error.h"
#include "runtime/threads.h"
#include "test_support.h"

namespace meshflow {
namespace {

constexpr float kSequenceVoxel = 0.05f;

ReconstructionConfig sequence_config() {
  ReconstructionConfig c;
  c.voxelize.voxel_size = kSequenceVoxel;
  return c;
}

synthetic::ScanSequenceConfig small_sequence(int frames) {
  synthetic::ScanSequenceConfig c;
  c.frames = frames;
  c.scan.azimuth_steps = 240;
  c.scan.elevation_steps = 80;
  return c;
}

TEST(SequenceRunner, SyntheticSequenceReconstructsInOrderWithinAQuarterVoxel) {
  const synthetic::Scene scene = synthetic::demo_room_scene();
  const auto seq = synthetic::make_scan_sequence(scene, small_sequence(5));
  ReconstructionPipeline pipeline(sequence_config(), 3);
  std::vector<std::size_t> order;
  const SequenceRunStats stats = run_sequence(pipeline, *seq, {}, [&](const Frame& f) {
    order.push_back(f.source_index);
    ASSERT_TRUE(f.ok()) << f.error;
    const auto err = test::vertex_errors(
        f.mesh, [&](const Eigen::Vector3f& p) { return synthetic::surface_distance(scene, p); });
    std::printf("[ accuracy ] frame %zu: mean %.4f voxel\n", f.source_index,
                err.mean / kSequenceVoxel);
    EXPECT_LT(err.mean / kSequenceVoxel, 0.25);
    EXPECT_GT(f.mesh.triangles.size(), 1000u);
  });
  EXPECT_EQ(order, (std::vector<std::size_t>{0, 1, 2, 3, 4}));
  EXPECT_EQ(stats.frames_ok, 5u);
  EXPECT_TRUE(stats.records.empty()) << "kept only when asked (keep_records)";
  const auto stages = stats.stages.summaries();
  ASSERT_EQ(stages.size(), 8u);
  for (const StageSummary& s : stages) EXPECT_EQ(s.calls, 5u) << s.stage;
  EXPECT_GT(stats.frames_per_second(), 0.0);
}

TEST(SequenceRunner, SameMeshesWithOneAndTwoThreads) {
  const auto seq = synthetic::make_scan_sequence(synthetic::demo_room_scene(), small_sequence(3));
  auto meshes = [&](int threads) {
    ThreadLimit limit(threads);
    ReconstructionPipeline pipeline(sequence_config(), 2);
    std::vector<TriangleMesh> out;
    run_sequence(pipeline, *seq, {}, [&](const Frame& f) { out.push_back(f.mesh); });
    return out;
  };
  const auto one = meshes(1), two = meshes(2);
  ASSERT_EQ(one.size(), two.size());
  ASSERT_EQ(one.size(), 3u);
  for (std::size_t i = 0; i < one.size(); ++i) {
    EXPECT_GT(one[i].triangles.size(), 100u);
    EXPECT_EQ(one[i].vertices, two[i].vertices);
    EXPECT_EQ(one[i].triangles, two[i].triangles);
  }
}

// A sequence whose frame 2 is broken: the run reports it and goes on; strict mode stops.
class BrokenSequence final : public io::Sequence {
 public:
  std::size_t size() const override { return 6; }
  io::SequenceFrame frame(std::size_t i) const override {
    return {i,
            0.0,
            "frame" + std::to_string(i),
            [i] {
              if (i == 2)
                throw Error("scan002.3d", "line 7", "expected x y z (cm), found 2 values");
              PointCloud c;
              for (int x = 0; x < 30; ++x)
                for (int y = 0; y < 30; ++y) c.positions.emplace_back(0.02f * x, 0.02f * y, 0.0f);
              c.sensor_origin = Eigen::Vector3f(0.3f, 0.3f, 1.0f);
              c.has_sensor_origin = true;
              return c;
            },
            {}};
  }
  std::string description() const override { return "broken"; }
};

TEST(SequenceRunner, BadFrameIsCountedAndTheRunContinues) {
  BrokenSequence seq;
  ReconstructionPipeline pipeline(sequence_config(), 4);
  std::vector<std::size_t> delivered;
  const SequenceRunStats stats = run_sequence(pipeline, seq, {}, [&](const Frame& f) {
    delivered.push_back(f.source_index);
    if (f.source_index == 2) {
      EXPECT_EQ(f.failed_stage, "read");
      EXPECT_NE(f.error.find("scan002.3d: line 7"), std::string::npos);
    }
  });
  EXPECT_EQ(stats.frames_ok, 5u);
  EXPECT_EQ(stats.frames_failed, 1u);
  EXPECT_FALSE(stats.stopped_early);
  EXPECT_EQ(delivered, (std::vector<std::size_t>{0, 1, 2, 3, 4, 5}));
}

TEST(SequenceRunner, StrictStopsAtTheFirstBadFrame) {
  BrokenSequence seq;
  ReconstructionPipeline pipeline(sequence_config(), 1);
  std::vector<std::size_t> delivered;
  const SequenceRunStats stats = run_sequence(
      pipeline, seq, {1, 0, true}, [&](const Frame& f) { delivered.push_back(f.source_index); });
  EXPECT_TRUE(stats.stopped_early);
  EXPECT_EQ(stats.frames_failed, 1u);
  EXPECT_EQ(delivered, (std::vector<std::size_t>{0, 1, 2}));
}

TEST(SequenceRunner, EveryAndMaxFramesSelectFrames) {
  BrokenSequence seq;
  ReconstructionPipeline pipeline(sequence_config(), 2);
  std::vector<std::size_t> delivered;
  run_sequence(pipeline, seq, {3, 0, false},
               [&](const Frame& f) { delivered.push_back(f.source_index); });
  EXPECT_EQ(delivered, (std::vector<std::size_t>{0, 3}));
  delivered.clear();
  run_sequence(pipeline, seq, {1, 2, false},
               [&](const Frame& f) { delivered.push_back(f.source_index); });
  EXPECT_EQ(delivered, (std::vector<std::size_t>{0, 1}));
}

TEST(SequenceRunner, PacedReplayReleasesEachFrameOnItsScheduleAndLoops) {
  const auto seq = synthetic::make_scan_sequence(synthetic::demo_room_scene(), small_sequence(3));
  ReconstructionPipeline pipeline(sequence_config(), 2);
  SequenceRunOptions options;
  options.rate_hz = 40.0;
  options.loops = 2;
  std::vector<std::size_t> sources;
  std::vector<std::uint64_t> seqs;
  std::vector<double> released;
  const SequenceRunStats stats = run_sequence(pipeline, *seq, options, [&](const Frame& f) {
    EXPECT_TRUE(f.ok()) << f.error;
    EXPECT_GE(monotonic_seconds(), f.submitted_s) << "delivered before its release";
    sources.push_back(f.source_index);
    seqs.push_back(f.seq);
    released.push_back(f.submitted_s);
  });
  EXPECT_EQ(stats.frames_ok, 6u);
  EXPECT_EQ(sources, (std::vector<std::size_t>{0, 1, 2, 0, 1, 2}));
  EXPECT_EQ(seqs, (std::vector<std::uint64_t>{0, 1, 2, 3, 4, 5}));
  // The n-th frame's release is the schedule's (n / rate after the first), whatever the graph
  // did meanwhile; the run takes at least the schedule.
  for (std::size_t i = 0; i < released.size(); ++i)
    EXPECT_NEAR(released[i] - released[0], static_cast<double>(i) / 40.0, 1e-9) << i;
  EXPECT_GE(stats.wall_s, 5.0 / 40.0);
}

}  // namespace
}  // namespace meshflow
