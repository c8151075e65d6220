#include "graph/live_pipeline.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <future>
#include <limits>
#include <map>
#include <mutex>
#include <thread>

#include "nodes/synthetic/depth_sequence.h"
#include "nodes/synthetic/shapes.h"
#include "runtime/error.h"

namespace meshflow {
namespace {

LiveConfig live_sphere_config(LivePolicy policy, std::size_t in_flight, std::size_t waiting) {
  LiveConfig c;
  c.reconstruction.voxelize.voxel_size = 0.1f;
  c.reconstruction.normals.orientation = NormalOrientation::kAwayFromViewpoint;
  c.policy = policy;
  c.frames_in_flight = in_flight;
  c.max_waiting = waiting;
  return c;
}

PointCloud sphere(int i) {
  return synthetic::sample_surface(
      synthetic::Sphere{{0, 0, 0}, 1.0f + 0.05f * static_cast<float>(i)}, 0.05f, 0.0f, 1);
}

// What the callback saw, guarded for reading from the test thread.
struct Received {
  std::mutex mutex;
  std::vector<LiveResult> results;
  void add(LiveResult& r) {
    std::lock_guard<std::mutex> lock(mutex);
    results.push_back(std::move(r));
  }
};

TEST(LivePipeline, QueuePolicyDeliversEveryFrameInOrderWithFailuresReported) {
  Received got;
  LivePipeline live(live_sphere_config(LivePolicy::kQueue, 2, 16),
                    [&](LiveResult& r) { got.add(r); });
  for (int i = 0; i < 10; ++i) {
    const auto push = live.push(i == 4 ? PointCloud{} : sphere(i));  // frame 4 is empty
    EXPECT_EQ(push.status, LivePipeline::PushStatus::kAccepted);
    EXPECT_EQ(push.seq, static_cast<std::uint64_t>(i));
  }
  live.flush();
  ASSERT_EQ(got.results.size(), 10u);
  for (std::size_t i = 0; i < 10; ++i) {
    const LiveResult& r = got.results[i];
    EXPECT_EQ(r.seq, i);
    if (i == 4) {
      EXPECT_FALSE(r.ok);
      EXPECT_NE(r.error.find("frame 4"), std::string::npos) << r.error;
      continue;
    }
    EXPECT_TRUE(r.ok) << r.error;
    EXPECT_GT(r.mesh.triangles.size(), 100u);
    EXPECT_GE(r.timings.size(), 8u);
    EXPECT_GT(r.latency_s, 0.0);
  }
  const LiveStats s = live.stats();
  EXPECT_EQ(s.pushed, 10u);
  EXPECT_EQ(s.delivered, 10u);
  EXPECT_EQ(s.failed, 1u);
  EXPECT_EQ(s.dropped + s.rejected, 0u);
  EXPECT_EQ(s.waiting + s.in_flight, 0u);
  EXPECT_GT(s.latency_p99_s, 0.0);
  EXPECT_GE(s.latency_p99_s, s.latency_p50_s);
}

// A cloud that gives no surface is delivered as a failed frame with the reason, never as an
// ok frame with an empty mesh.
TEST(LivePipeline, ACloudWithoutASurfaceIsDeliveredFailed) {
  Received got;
  LivePipeline live(live_sphere_config(LivePolicy::kQueue, 1, 4),
                    [&](LiveResult& r) { got.add(r); });
  PointCloud three;
  three.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  live.push(std::move(three));
  live.push(sphere(0));
  live.flush();
  ASSERT_EQ(got.results.size(), 2u);
  EXPECT_FALSE(got.results[0].ok) << got.results[0].mesh.triangles.size() << " triangles";
  EXPECT_FALSE(got.results[0].failed_stage.empty());
  EXPECT_NE(got.results[0].error.find("triangle"), std::string::npos) << got.results[0].error;
  EXPECT_TRUE(got.results[1].ok) << got.results[1].error;
  EXPECT_EQ(live.stats().failed, 1u);
}

// The same on the per-frame triangulation path: a depth image without a valid pixel.
TEST(LivePipeline, ADepthImageWithoutMeasurementsIsDeliveredFailedWhenTriangulating) {
  synthetic::DepthSequenceConfig camera;
  camera.frames = 1;
  camera.intrinsics = PinholeIntrinsics{160, 120, 131.25f, 131.25f, 79.5f, 59.5f};
  const auto seq = synthetic::make_depth_sequence(synthetic::demo_room_scene(), camera);
  LiveConfig config;
  config.policy = LivePolicy::kQueue;
  config.triangulate_depth_maps = true;
  Received got;
  LivePipeline live(config, [&](LiveResult& r) { got.add(r); });
  DepthFrame blank = seq->frame(0).load_depth();
  blank.depth = Image(blank.depth.rows(), blank.depth.cols(), PixelFormat::U16);  // all 0
  live.push(std::move(blank));
  live.flush();
  ASSERT_EQ(got.results.size(), 1u);
  EXPECT_FALSE(got.results[0].ok) << got.results[0].mesh.vertices.size() << " vertices";
  EXPECT_EQ(got.results[0].failed_stage, "triangulate");
  EXPECT_NE(got.results[0].error.find("no triangle"), std::string::npos) << got.results[0].error;
}

// The embedding API hands the callback the compressed bytes when asked: they decode to the
// frame's mesh (positions within the quantisation step).
TEST(LivePipeline, CallbackGetsTheCompressedMeshWhenAsked) {
  for (const MeshCompression method :
       {MeshCompression::kEdgebreaker, MeshCompression::kProgressive}) {
    Received got;
    LiveConfig config = live_sphere_config(LivePolicy::kQueue, 2, 8);
    config.reconstruction.compression = method;
    {
      LivePipeline live(config, [&](LiveResult& r) { got.add(r); });
      for (int i = 0; i < 3; ++i) live.push(sphere(i));
      live.flush();
    }
    ASSERT_EQ(got.results.size(), 3u);
    for (const LiveResult& r : got.results) {
      ASSERT_TRUE(r.ok) << r.error;
      ASSERT_FALSE(r.compressed.empty());
      EXPECT_EQ(r.timings.back().stage, std::string("compress"));
      const TriangleMesh decoded = compress::decompress_mesh(r.compressed, "live");
      EXPECT_EQ(decoded.triangles.size(), r.mesh.triangles.size());
      EXPECT_EQ(decoded.vertices.size(), r.mesh.vertices.size());
      EXPECT_LT(8.0 * static_cast<double>(r.compressed.size()) /
                    static_cast<double>(r.mesh.triangles.size()),
                64.0);
    }
  }
}

TEST(LivePipeline, QueuePolicyRefusesFramesWhileFullAndLosesNoAcceptedOne) {
  Received got;
  LivePipeline live(live_sphere_config(LivePolicy::kQueue, 1, 2),
                    [&](LiveResult& r) { got.add(r); });
  std::vector<PointCloud> clouds;
  for (int i = 0; i < 12; ++i) clouds.push_back(sphere(i));
  std::vector<std::uint64_t> accepted;
  for (int i = 0; i < 12; ++i) {
    const auto push = live.push(std::move(clouds[static_cast<std::size_t>(i)]));
    if (push.status == LivePipeline::PushStatus::kAccepted) accepted.push_back(push.seq);
    EXPECT_LE(live.stats().waiting, 2u);
  }
  live.flush();
  const LiveStats s = live.stats();
  EXPECT_GT(s.rejected, 0u);  // 12 pushes in microseconds against ~10 ms frames
  EXPECT_EQ(s.rejected + accepted.size(), 12u);
  ASSERT_EQ(got.results.size(), accepted.size());
  for (std::size_t i = 0; i < accepted.size(); ++i) EXPECT_EQ(got.results[i].seq, accepted[i]);
}

TEST(LivePipeline, RealtimePolicyDropsTheOldestAndBoundsTheFramesAhead) {
  // Frames delivered between a frame's push and its own delivery are the latency in frames:
  // at most frames_in_flight + max_waiting (anything older was dropped).
  std::mutex mutex;
  std::map<std::uint64_t, std::uint64_t> delivered_at_push;
  std::uint64_t delivered = 0;
  std::vector<std::uint64_t> order, frames_ahead;
  LivePipeline live(live_sphere_config(LivePolicy::kRealtime, 1, 1), [&](LiveResult& r) {
    std::lock_guard<std::mutex> lock(mutex);
    order.push_back(r.seq);
    frames_ahead.push_back(delivered - delivered_at_push.at(r.seq));
    ++delivered;
  });
  const std::vector<PointCloud> clouds = {sphere(0), sphere(1), sphere(2)};
  for (int i = 0; i < 30; ++i) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      delivered_at_push[static_cast<std::uint64_t>(i)] = delivered;
    }
    const auto push = live.push(clouds[static_cast<std::size_t>(i % 3)]);
    EXPECT_NE(push.status, LivePipeline::PushStatus::kRejected);
    EXPECT_LE(live.stats().waiting, 1u);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  live.flush();
  const LiveStats s = live.stats();
  EXPECT_GT(s.dropped, 0u);
  EXPECT_EQ(s.delivered + s.dropped, 30u);
  ASSERT_EQ(order.size(), s.delivered);
  EXPECT_TRUE(std::is_sorted(order.begin(), order.end()));
  EXPECT_EQ(order.back(), 29u);  // the newest frame is never the one dropped
  for (std::uint64_t ahead : frames_ahead) EXPECT_LE(ahead, 2u);
}

TEST(LivePipeline, DestructionWithFramesInFlightMakesNoLaterCallback) {
  std::atomic<int> calls{0};
  {
    LivePipeline live(live_sphere_config(LivePolicy::kQueue, 2, 8), [&](LiveResult&) { ++calls; });
    std::vector<PointCloud> clouds;
    for (int i = 0; i < 8; ++i) clouds.push_back(sphere(i));
    for (auto& cloud : clouds) live.push(std::move(cloud));
  }  // destroyed at once: waiting frames discarded, in-flight ones finished silently
  const int at_destruction = calls.load();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_EQ(calls.load(), at_destruction);
  EXPECT_LT(at_destruction, 8);
}

TEST(LivePipeline, PushFromOneThreadWhileCallbacksRunOnOthersAndDepthFramesWork) {
  const synthetic::Scene scene = synthetic::demo_room_scene();
  synthetic::DepthSequenceConfig camera;
  camera.frames = 3;
  camera.intrinsics = PinholeIntrinsics{160, 120, 131.25f, 131.25f, 79.5f, 59.5f};
  const auto seq = synthetic::make_depth_sequence(scene, camera);
  LiveConfig config;
  config.reconstruction.voxelize.voxel_size = 0.05f;
  config.policy = LivePolicy::kQueue;
  config.max_waiting = 8;
  Received got;
  std::atomic<bool> callback_on_pusher{false};
  const auto pusher = std::this_thread::get_id();
  LivePipeline live(config, [&](LiveResult& r) {
    if (std::this_thread::get_id() == pusher) callback_on_pusher = true;
    got.add(r);
  });
  for (std::size_t i = 0; i < seq->size(); ++i) live.push(seq->frame(i).load_depth());
  live.flush();
  EXPECT_FALSE(callback_on_pusher.load());
  ASSERT_EQ(got.results.size(), 3u);
  for (const LiveResult& r : got.results) {
    EXPECT_TRUE(r.ok) << r.error;
    EXPECT_GT(r.mesh.triangles.size(), 1000u);
  }
}

TEST(LivePipeline, TriangulatesDepthMapsPerFrameAndFailsBadFramesClearly) {
  synthetic::DepthSequenceConfig camera;
  camera.frames = 2;
  camera.intrinsics = PinholeIntrinsics{160, 120, 131.25f, 131.25f, 79.5f, 59.5f};
  const auto seq = synthetic::make_depth_sequence(synthetic::demo_room_scene(), camera);
  LiveConfig config;
  config.policy = LivePolicy::kQueue;
  config.max_waiting = 8;  // room for every frame below: none refused however fast they come
  config.triangulate_depth_maps = true;
  config.reconstruction.triangulation.method = DepthTriangulationMethod::kRestrictedQuadtree;
  Received got;
  LivePipeline live(config, [&](LiveResult& r) { got.add(r); });
  live.push(seq->frame(0).load_depth());
  live.push(sphere(0));  // not a depth image
  DepthFrame eight_bit = seq->frame(1).load_depth();
  eight_bit.depth = Image(eight_bit.depth.rows(), eight_bit.depth.cols(),
                          PixelFormat::U8);  // a frame an embedder might get wrong
  live.push(std::move(eight_bit));
  DepthFrame lost = seq->frame(1).load_depth();
  lost.T_world_camera.translation().x() = std::numeric_limits<float>::quiet_NaN();
  live.push(std::move(lost));
  live.push(seq->frame(1).load_depth());
  live.flush();
  ASSERT_EQ(got.results.size(), 5u);
  EXPECT_TRUE(got.results[0].ok) << got.results[0].error;
  EXPECT_GT(got.results[0].mesh.triangles.size(), 500u);
  EXPECT_EQ(got.results[0].timings.size(), 2u);  // read, triangulate
  EXPECT_FALSE(got.results[1].ok);
  EXPECT_NE(got.results[1].error.find("depth image"), std::string::npos) << got.results[1].error;
  EXPECT_FALSE(got.results[2].ok);
  EXPECT_NE(got.results[2].error.find("expected a U16 or F32 image, got U8"), std::string::npos)
      << got.results[2].error;
  EXPECT_FALSE(got.results[3].ok);
  EXPECT_NE(got.results[3].error.find("T_world_camera"), std::string::npos) << got.results[3].error;
  EXPECT_TRUE(got.results[4].ok) << got.results[4].error;
}

// Stage spans (start, end) of six frames pushed at once, with `threads` arena threads. (How
// many of several threads actually join is up to oneTBB's scheduler, so only the one-thread
// case is asserted.)
std::vector<std::pair<double, double>> stage_spans(int threads) {
  LiveConfig config = live_sphere_config(LivePolicy::kQueue, 4, 8);
  config.threads = threads;
  Received got;
  LivePipeline live(config, [&](LiveResult& r) { got.add(r); });
  for (int i = 0; i < 6; ++i) live.push(sphere(i));
  live.flush();
  EXPECT_EQ(got.results.size(), 6u);
  std::vector<std::pair<double, double>> spans;
  for (const LiveResult& r : got.results)
    for (const StageRecord& t : r.timings) spans.emplace_back(t.start_s, t.end_s);
  std::sort(spans.begin(), spans.end());
  return spans;
}

std::size_t overlaps(const std::vector<std::pair<double, double>>& spans) {
  std::size_t n = 0;
  for (std::size_t i = 1; i < spans.size(); ++i) n += spans[i].first < spans[i - 1].second ? 1 : 0;
  return n;
}

TEST(LivePipeline, OneThreadRunsOneStageAtATime) { EXPECT_EQ(overlaps(stage_spans(1)), 0u); }

TEST(LivePipeline, PushReturnsWhileEveryPipelineThreadIsBusy) {
  LiveConfig config = live_sphere_config(LivePolicy::kQueue, 2, 8);
  config.threads = 1;
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  std::atomic<bool> in_callback{false};
  LivePipeline live(config, [&](LiveResult&) {
    in_callback = true;
    released.wait();  // holds the pipeline's only thread
  });
  live.push(sphere(0));
  while (!in_callback) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  const std::vector<PointCloud> clouds = {sphere(1), sphere(2), sphere(3)};
  auto pushes = std::async(std::launch::async, [&] {
    for (const auto& c : clouds) live.push(c);
  });
  EXPECT_EQ(pushes.wait_for(std::chrono::seconds(10)), std::future_status::ready);
  release.set_value();
  pushes.wait();
  live.flush();
  EXPECT_EQ(live.stats().delivered, 4u);
}

TEST(LivePipeline, EmptyCallbackIsAnError) {
  EXPECT_THROW(LivePipeline(LiveConfig{}, nullptr), Error);
}

}  // namespace
}  // namespace meshflow
