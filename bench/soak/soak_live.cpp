// meshflow_soak_live: a long run of the embedding API (LivePipeline) with faults mixed in.
//
//   meshflow_soak_live [--frames 10000] [--policy queue|realtime|both] [--rate 200]
//                      [--fault-share 0.05] [--size 160x120] [--threads 0] [--seed 1]
//
// Pushes --frames synthetic depth frames (the demo room seen by a camera turning on the spot, 32
// distinct views rendered once) at --rate frames/s into a LivePipeline with each policy. A
// --fault-share of them are broken the three ways a driver breaks them: an unreadable frame (no
// depth image), a frame without one valid pixel, a NaN pose. It checks, and prints:
//   - accounting: pushed = delivered + dropped + rejected, every delivered broken frame failed
//     and every delivered good frame succeeded, callbacks in push order;
//   - memory: every 10 % of the frames the pipeline is flushed (nothing in flight) and the heap
//     bytes in use (glibc's mallinfo2: this program uses the system allocator, not the
//     scalable one the CLI links, so that the figure is exact) and the resident set sampled;
//     the heap in use at the end must be within 1 % of the heap after the first 20 % (the
//     warm-up: thread and pool set-up). Resident memory is reported, not checked: it swings by
//     megabytes as the allocator caches and returns pages;
//   - latency (push to callback) p50 / p95 / p99 / max over every delivered frame.
// Exit status 0 when every check holds, 1 otherwise. Not a ctest: it runs for minutes.

#include <malloc.h>
#include <unistd.h>
#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "graph/live_pipeline.h"
#include "nodes/synthetic/depth_sequence.h"
#include "nodes/synthetic/scan_simulator.h"
#include "runtime/tracing.h"

namespace {

using meshflow::DepthFrame;
using meshflow::LiveConfig;
using meshflow::LivePipeline;
using meshflow::LivePolicy;
using meshflow::LiveResult;

struct Options {
  std::size_t frames = 10000;
  std::string policy = "both";
  double rate_hz = 200.0;
  double fault_share = 0.05;
  int width = 160, height = 120;
  int threads = 0;
  unsigned seed = 1;
};

[[noreturn]] void usage(const char* problem) {
  std::fprintf(stderr,
               "meshflow_soak_live: %s\nusage: meshflow_soak_live [--frames N] "
               "[--policy queue|realtime|both] [--rate HZ] [--fault-share F] [--size WxH] "
               "[--threads N] [--seed S]\n",
               problem);
  std::exit(2);
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (i + 1 >= argc) usage(("missing value after " + flag).c_str());
    const std::string value = argv[++i];
    if (flag == "--frames")
      o.frames = std::stoul(value);
    else if (flag == "--policy")
      o.policy = value;
    else if (flag == "--rate")
      o.rate_hz = std::stod(value);
    else if (flag == "--fault-share")
      o.fault_share = std::stod(value);
    else if (flag == "--threads")
      o.threads = std::stoi(value);
    else if (flag == "--seed")
      o.seed = static_cast<unsigned>(std::stoul(value));
    else if (flag == "--size") {
      if (std::sscanf(value.c_str(), "%dx%d", &o.width, &o.height) != 2) usage("--size WxH");
    } else {
      usage(("unknown option " + flag).c_str());
    }
  }
  if (o.policy != "queue" && o.policy != "realtime" && o.policy != "both")
    usage("--policy is queue, realtime or both");
  if (!(o.rate_hz > 0.0) || o.frames < 10 || o.width < 16 || o.height < 16)
    usage("need --rate > 0, --frames >= 10 and --size of at least 16x16");
  return o;
}

// Resident set size of this process in bytes (/proc/self/statm).
std::size_t resident_bytes() {
  std::ifstream statm("/proc/self/statm");
  std::size_t pages = 0, resident = 0;
  statm >> pages >> resident;
  return resident * static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
}

// Bytes the program's heap holds in allocated blocks (glibc mallinfo2: arena and mmap-ed).
std::size_t heap_in_use() {
  const struct mallinfo2 info = mallinfo2();
  return info.uordblks + info.hblkhd;
}

enum class Fault { kNone, kUnreadable, kAllInvalid, kNanPose };

DepthFrame broken(const DepthFrame& good, Fault fault) {
  DepthFrame f = good;
  if (fault == Fault::kUnreadable) f.depth = meshflow::Image();
  if (fault == Fault::kAllInvalid)
    f.depth = meshflow::Image(good.depth.rows(), good.depth.cols(), good.depth.format());
  if (fault == Fault::kNanPose)
    f.T_world_camera.translation().x() = std::numeric_limits<float>::quiet_NaN();
  return f;
}

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  const std::size_t k = static_cast<std::size_t>(p * static_cast<double>(values.size() - 1));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

// One soak with one policy; returns true when every check holds.
bool soak(const Options& o, LivePolicy policy, const std::vector<DepthFrame>& views) {
  const char* name = policy == LivePolicy::kQueue ? "queue" : "realtime";
  std::mt19937 rng(o.seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<Fault> faults(o.frames, Fault::kNone);
  for (Fault& f : faults)
    if (uniform(rng) < o.fault_share) f = static_cast<Fault>(1 + rng() % 3);

  std::mutex mutex;  // guards the three below (the callback runs on a pipeline thread)
  std::vector<double> latencies;
  std::size_t wrong_outcome = 0, out_of_order = 0;
  std::uint64_t last_seq = 0;
  bool first = true;
  latencies.reserve(o.frames);

  LiveConfig config;
  config.policy = policy;
  config.threads = o.threads;
  config.reconstruction.voxelize.voxel_size = 0.05f;
  {
    LivePipeline live(config, [&](LiveResult& r) {
      std::lock_guard<std::mutex> lock(mutex);
      latencies.push_back(r.latency_s);
      const bool expect_ok = faults[r.seq] == Fault::kNone;
      if (r.ok != expect_ok) {
        if (++wrong_outcome <= 5)
          std::fprintf(stderr, "  frame %llu: %s%s\n", static_cast<unsigned long long>(r.seq),
                       r.ok ? "succeeded although broken" : "failed: ", r.error.c_str());
      }
      if (!first && r.seq <= last_seq) ++out_of_order;
      first = false;
      last_seq = r.seq;
    });
    std::vector<std::size_t> heap_samples, rss_samples;  // at each checkpoint
    const auto period = std::chrono::duration<double>(1.0 / o.rate_hz);
    auto next = std::chrono::steady_clock::now();
    const double start = meshflow::monotonic_seconds();
    for (std::size_t i = 0; i < o.frames; ++i) {
      const DepthFrame& view = views[i % views.size()];
      live.push(faults[i] == Fault::kNone ? view : broken(view, faults[i]));
      if ((i + 1) % (o.frames / 10) == 0) {  // a checkpoint: quiet, then sampled
        live.flush();
        // The last frame's buffers are freed on a pipeline thread just after its callback.
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        heap_samples.push_back(heap_in_use());
        rss_samples.push_back(resident_bytes());
      }
      next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
      std::this_thread::sleep_until(next);
    }
    live.flush();
    const double seconds = meshflow::monotonic_seconds() - start;
    const meshflow::LiveStats s = live.stats();

    std::lock_guard<std::mutex> lock(mutex);
    const bool accounted = s.pushed == o.frames && s.pushed == s.delivered + s.dropped + s.rejected;
    const double early = static_cast<double>(heap_samples[1]);
    const double late = static_cast<double>(heap_samples.back());
    const double growth = 100.0 * (late - early) / early;
    std::size_t broken_pushed = 0;
    for (Fault f : faults) broken_pushed += f != Fault::kNone ? 1 : 0;
    std::printf("policy %-8s %zu frames in %.1f s at %.0f Hz (%zu broken), %d x %d, %d threads\n",
                name, o.frames, seconds, o.rate_hz, broken_pushed, o.width, o.height, o.threads);
    std::printf(
        "  accounting  pushed %llu = delivered %llu (failed %llu) + dropped %llu + rejected %llu: "
        "%s\n",
        static_cast<unsigned long long>(s.pushed), static_cast<unsigned long long>(s.delivered),
        static_cast<unsigned long long>(s.failed), static_cast<unsigned long long>(s.dropped),
        static_cast<unsigned long long>(s.rejected), accounted ? "exact" : "MISMATCH");
    std::printf("  outcomes    %zu delivered frames with the wrong outcome, %zu out of order\n",
                wrong_outcome, out_of_order);
    std::printf("  memory      heap in use %.3f MB after warm-up, %.3f MB at the end: %+.3f %%\n",
                early / 1e6, late / 1e6, growth);
    std::printf("  checkpoints heap / resident MB at 10, 20, ... 100 %% of the frames:");
    for (std::size_t k = 0; k < heap_samples.size(); ++k)
      std::printf(" %.2f/%.1f", static_cast<double>(heap_samples[k]) / 1e6,
                  static_cast<double>(rss_samples[k]) / 1e6);
    std::printf("\n");
    std::printf("  latency     p50 %.1f ms, p95 %.1f ms, p99 %.1f ms, max %.1f ms\n",
                1e3 * percentile(latencies, 0.50), 1e3 * percentile(latencies, 0.95),
                1e3 * percentile(latencies, 0.99), 1e3 * percentile(latencies, 1.0));
    const bool ok = accounted && wrong_outcome == 0 && out_of_order == 0 && growth < 1.0;
    std::printf("  %s\n", ok ? "PASS" : "FAIL");
    return ok;
  }
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  meshflow::synthetic::DepthSequenceConfig c;
  c.frames = 32;
  c.intrinsics = meshflow::synthetic::scaled_default_camera(o.width, o.height);
  const auto sequence =
      meshflow::synthetic::make_depth_sequence(meshflow::synthetic::demo_room_scene(), c);
  std::vector<DepthFrame> views;
  for (std::size_t i = 0; i < sequence->size(); ++i)
    views.push_back(sequence->frame(i).load_depth());
  bool ok = true;
  if (o.policy != "realtime") ok = soak(o, LivePolicy::kQueue, views) && ok;
  if (o.policy != "queue") ok = soak(o, LivePolicy::kRealtime, views) && ok;
  return ok ? 0 : 1;
}
