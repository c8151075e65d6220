// meshflow live: replays a sequence at a fixed rate through the embedding API (LivePipeline), as
// a sensor loop would, and reports latency percentiles and drops.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "graph/live_pipeline.h"
#include "runtime/error.h"
#include "tools/cli_checks.h"
#include "tools/commands.h"
#include "tools/console.h"
#include "tools/pipeline_options.h"
#include "tools/run_view.h"

namespace meshflow::cli {
namespace {

struct LiveOptions {
  SequenceArgument sequence;
  PipelineOptions pipeline;
  double rate_hz = 30.0;
  std::string policy = "realtime";
  std::size_t waiting = 2;
  std::size_t loops = 1;
  TriangulationOptions triangulation;
  bool warm_up = true;  ///< --no-warm-up: time a cold start
  ServeOptions serve;   ///< --serve: show the meshes in a browser
};

using SensorFrame = std::variant<PointCloud, DepthFrame>;

// The warm-up meshes every frame once, then the frames over again until it has meshed this many
// or spent this long: the allocator's pools keep growing, with page faults, for the first 11-15
// Redwood frames of a process (bench/RESULTS.md, sessions 24-25), and a five-frame warm-up left
// that to the timed replay; the time bound keeps a slow volumetric sequence's warm-up short.
constexpr std::size_t kWarmUpFrames = 32;
constexpr double kWarmUpSeconds = 1.0;

// The frames the "sensor" will deliver, loaded up front so the loop only pushes. A frame that
// cannot be read is reported on stderr (its number, file and the reader's message) and left
// out, as `meshflow run` does; `unreadable` counts them.
std::vector<SensorFrame> load_frames(const io::Sequence& sequence, const SequenceArgument& a,
                                     std::size_t& unreadable) {
  std::vector<SensorFrame> frames;
  unreadable = 0;
  for (std::size_t i = 0; i < sequence.size(); i += a.every) {
    if (a.max_frames > 0 && frames.size() + unreadable == a.max_frames) break;
    const io::SequenceFrame f = sequence.frame(i);
    try {
      if (f.load_depth)
        frames.emplace_back(f.load_depth());
      else
        frames.emplace_back(f.load());
    } catch (const Error& e) {
      std::fprintf(stderr, "meshflow: frame %zu (%s) skipped: %s\n", i, f.name.c_str(), e.what());
      ++unreadable;
    }
  }
  return frames;
}

using Clock = std::chrono::steady_clock;

// Meshes `frames` in a throwaway pipeline of `config` (queue policy: nothing dropped) so that
// worker threads and allocator pools start before the timed replay: every frame once, then the
// frames over again, flushed after each round, up to kWarmUpFrames in all or kWarmUpSeconds.
// Prints how many frames it meshed.
void warm_up(const LiveConfig& config, const std::vector<SensorFrame>& frames) {
  LiveConfig queue = config;
  queue.policy = LivePolicy::kQueue;
  queue.max_waiting = frames.size();
  const auto start = Clock::now();
  const auto seconds = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  LivePipeline warm(queue, [](LiveResult&) {});
  std::size_t warmed = 0;
  do {
    const std::size_t round =
        warmed == 0 ? frames.size() : std::min(frames.size(), kWarmUpFrames - warmed);
    for (std::size_t i = 0; i < round; ++i)
      std::visit([&](const auto& frame) { warm.push(frame); }, frames[i]);
    warm.flush();
    warmed += round;
  } while (warmed < kWarmUpFrames && seconds() < kWarmUpSeconds);
  report("warm-up    %zu frames meshed in %.2f s (not timed)\n", warmed, seconds());
}

void run_live(const LiveOptions& o) {
  const auto sequence = open_sequence_argument(o.sequence);
  std::size_t unreadable = 0;
  const std::vector<SensorFrame> frames = load_frames(*sequence, o.sequence, unreadable);
  if (frames.empty())
    throw Error(sequence->description(), "frames",
                unreadable > 0 ? "none readable (" + std::to_string(unreadable) + " skipped)"
                               : std::string("none selected"));
  LiveConfig config;
  config.reconstruction = o.pipeline.config();
  config.threads = o.pipeline.threads;
  config.frames_in_flight = o.sequence.in_flight;
  config.max_waiting = o.waiting;
  config.policy = o.policy == "queue" ? LivePolicy::kQueue : LivePolicy::kRealtime;
  config.triangulate_depth_maps = o.triangulation.enabled();
  o.triangulation.apply(config.reconstruction);
  if (o.warm_up) warm_up(config, frames);
  const std::unique_ptr<RunView> view = start_run_view(o.serve, "meshflow live");
  std::size_t triangles = 0;
  LivePipeline live(config, [&](LiveResult& r) {
    triangles += r.mesh.triangles.size();
    if (view) view->frame(r);
    if (!r.ok)
      std::fprintf(stderr, "meshflow: frame %llu failed in %s: %s\n",
                   static_cast<unsigned long long>(r.seq), r.failed_stage.c_str(), r.error.c_str());
  });
  report(
      "live       %s: %zu frames%s x %zu at %.1f Hz, policy %s, %zu in flight, %zu waiting\n",
      sequence->description().c_str(), frames.size(),
      unreadable > 0 ? (" (" + std::to_string(unreadable) + " unreadable, skipped)").c_str() : "",
      o.loops, o.rate_hz, o.policy.c_str(), config.frames_in_flight, config.max_waiting);
  const auto period = std::chrono::duration<double>(1.0 / o.rate_hz);
  const auto start = Clock::now();
  double worst_push_s = 0.0;
  const std::size_t pushes = frames.size() * o.loops;
  for (std::size_t i = 0; i < pushes; ++i) {
    std::this_thread::sleep_until(
        start + std::chrono::duration_cast<Clock::duration>(period * static_cast<double>(i)));
    const auto before = Clock::now();
    std::visit([&](const auto& frame) { live.push(frame); }, frames[i % frames.size()]);
    worst_push_s =
        std::max(worst_push_s, std::chrono::duration<double>(Clock::now() - before).count());
  }
  live.flush();
  const double wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  const LiveStats s = live.stats();
  report("frames     %llu pushed, %llu delivered (%llu failed), %llu dropped, %llu rejected\n",
         static_cast<unsigned long long>(s.pushed), static_cast<unsigned long long>(s.delivered),
         static_cast<unsigned long long>(s.failed), static_cast<unsigned long long>(s.dropped),
         static_cast<unsigned long long>(s.rejected));
  report("latency    p50 %.1f ms, p95 %.1f ms, p99 %.1f ms (push to callback)\n",
         1e3 * s.latency_p50_s, 1e3 * s.latency_p95_s, 1e3 * s.latency_p99_s);
  report("loop       longest push() %.3f ms; %.1f meshes/s over %.2f s; %zu triangles\n",
         1e3 * worst_push_s, static_cast<double>(s.delivered) / wall_s, wall_s, triangles);
  if (s.dropped > 0 && !config.triangulate_depth_maps)
    report(
        "note       frames were dropped: the volumetric path (normals, distance, extraction per "
        "frame) meshes fewer frames per second than --rate here; --triangulate rqt meshes each "
        "depth image directly and keeps up with 30 Hz depth cameras\n");
  if (view) view->finish_and_serve();
}

}  // namespace

void add_live_options(CLI::App* cmd) {
  auto o = std::make_shared<LiveOptions>();
  add_sequence_options(cmd, o->sequence);
  cmd->add_option("--rate", o->rate_hz, "Frames per second the replay pushes")
      ->check(number_in(0.1, 10000));
  cmd->add_option("--policy", o->policy,
                  "realtime (drop the oldest waiting frame) or queue (refuse while full)")
      ->check(CLI::IsMember({"realtime", "queue"}));
  cmd->add_option("--waiting", o->waiting, "Frames that may wait for a slot")
      ->check(CLI::Range(1, 1024));
  add_triangulation_options(cmd, o->triangulation);
  cmd->add_flag("--warm-up,!--no-warm-up", o->warm_up,
                "Before the timed replay (on by default; --no-warm-up times a cold start), mesh "
                "every frame once, then again up to " +
                    std::to_string(kWarmUpFrames) + " frames or " +
                    std::to_string(static_cast<int>(kWarmUpSeconds)) +
                    " s, in a throwaway pipeline (worker threads and allocator pools start), so "
                    "the first frames of the replay are not dropped for start-up costs");
  cmd->add_option("--loops", o->loops, "Replay the frames this many times")
      ->check(CLI::Range(1, 100000));
  add_pipeline_options(cmd, o->pipeline);
  cmd->get_option("--close")->excludes("--triangulate");  // no distance field to fill
  add_serve_options(cmd, o->serve);
  add_console_flags(cmd, false);
  cmd->callback([o] { run_live(*o); });
}

}  // namespace meshflow::cli
