// Frames/s of the whole pipeline over a sequence, sweeping threads x frames in flight.

#include <filesystem>
#include <memory>

#include "bench_support.h"
#include "graph/sequence_runner.h"
#include "nodes/synthetic/depth_sequence.h"
#include "nodes/synthetic/scan_sequence.h"
#include "runtime/threads.h"

namespace meshflow::bench {
namespace {

std::unique_ptr<io::Sequence> open_input_sequence(Input input) {
  switch (input) {
    case kSynthetic:
      return synthetic::make_scan_sequence(synthetic::demo_room_scene());
    case kSyntheticDepth:
      return synthetic::make_depth_sequence(synthetic::demo_room_scene());
    case kKurt3d:
      break;
    case kRedwood: {
      const std::string dir = data_dir() + "/rgbd_redwood";
      return std::filesystem::exists(dir) ? io::open_sequence(dir) : nullptr;
    }
  }
  if (!std::filesystem::exists(kurt3d_path())) return nullptr;
  return io::open_sequence(data_dir() + "/kurt3d");
}

// 5 cm for laser scans, 1 cm for 640 x 480 depth frames (the brief's per-frame setting).
float voxel_for(Input input) {
  return input == kRedwood || input == kSyntheticDepth ? 0.01f : 0.05f;
}

void BM_SequenceFramesPerSecond(benchmark::State& state) {
  const auto input = static_cast<Input>(state.range(2));
  const auto sequence = open_input_sequence(input);
  if (!sequence) {
    state.SkipWithError(("data not found under " + data_dir()).c_str());
    return;
  }
  ThreadLimit limit(static_cast<int>(state.range(0)));
  ReconstructionConfig config;
  config.voxelize.voxel_size = voxel_for(input);
  ReconstructionPipeline pipeline(config, static_cast<std::size_t>(state.range(1)));
  std::size_t frames = 0;
  for (auto _ : state) {
    const SequenceRunStats stats = run_sequence(pipeline, *sequence, {}, [](const Frame&) {});
    frames = stats.frames_ok;
    if (stats.frames_failed > 0) state.SkipWithError("a frame failed");
  }
  state.counters["frames/s"] = benchmark::Counter(static_cast<double>(frames),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_SequenceFramesPerSecond)
    ->ArgNames({"threads", "in_flight", "input"})
    ->ArgsProduct({{1, 2}, {1, 2, 4}, {kSynthetic, kKurt3d, kRedwood, kSyntheticDepth}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace meshflow::bench
