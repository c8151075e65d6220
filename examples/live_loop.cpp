// Embedding meshflow in a sensor loop. The frames of a recorded RGB-D sequence (a Redwood or
// TUM directory; without one, meshflow's synthetic depth camera turning in a room) are pushed
// into a LivePipeline at 30 frames/s, as a camera driver would; each mesh arrives in a callback
// on a pipeline thread, while the loop goes on. At the end: how many frames were meshed,
// dropped, failed, and the latency percentiles.
//
//   meshflow_example_live [SEQUENCE_DIR] [FRAMES]
//
// Build: part of meshflow's build (examples/); against an installed meshflow, link
// meshflow::graph (see tests/consumer/CMakeLists.txt).

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>

#include "graph/live_pipeline.h"
#include "nodes/io/sequence.h"
#include "nodes/synthetic/depth_sequence.h"
#include "nodes/synthetic/scan_simulator.h"
#include "runtime/error.h"

int main(int argc, char** argv) {
  using namespace meshflow;
  try {
    const std::unique_ptr<io::Sequence> sequence =
        argc > 1 ? io::open_sequence(argv[1])
                 : synthetic::make_depth_sequence(synthetic::demo_room_scene());
    const std::size_t frames =
        argc > 2 ? std::min<std::size_t>(std::strtoul(argv[2], nullptr, 10), sequence->size())
                 : sequence->size();
    std::printf("%s: pushing %zu frames at 30 frames/s\n", sequence->description().c_str(), frames);

    LiveConfig config;
    config.triangulate_depth_maps = true;  // per-frame depth-map meshes (restricted quadtree)
    config.reconstruction.triangulation.method = DepthTriangulationMethod::kRestrictedQuadtree;
    config.policy = LivePolicy::kRealtime;  // never fall behind the camera: drop the oldest
    std::atomic<std::size_t> triangles{0};
    LivePipeline live(config, [&triangles](LiveResult& r) {
      if (!r.ok) {
        std::printf("frame %llu failed: %s\n", static_cast<unsigned long long>(r.seq),
                    r.error.c_str());
        return;
      }
      triangles += r.mesh.triangles.size();
      std::printf("frame %llu: %zu triangles, %.1f ms after push\n",
                  static_cast<unsigned long long>(r.seq), r.mesh.triangles.size(),
                  1e3 * r.latency_s);
    });

    auto next = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < frames; ++i) {
      const io::SequenceFrame frame = sequence->frame(i);
      if (frame.load_depth) {
        live.push(frame.load_depth());
      } else {
        live.push(frame.load(), frame.timestamp_s);  // a cloud sequence: volumetric per frame
      }
      next += std::chrono::microseconds(33333);
      std::this_thread::sleep_until(next);  // the camera's frame period
    }
    live.flush();
    const LiveStats s = live.stats();
    std::printf(
        "pushed %llu, delivered %llu (failed %llu), dropped %llu; %zu triangles; latency p50 "
        "%.1f ms, p99 %.1f ms\n",
        static_cast<unsigned long long>(s.pushed), static_cast<unsigned long long>(s.delivered),
        static_cast<unsigned long long>(s.failed), static_cast<unsigned long long>(s.dropped),
        triangles.load(), 1e3 * s.latency_p50_s, 1e3 * s.latency_p99_s);
    return s.pushed == s.delivered + s.dropped + s.rejected && s.failed == 0 ? 0 : 1;
  } catch (const Error& e) {
    std::fprintf(stderr, "meshflow_example_live: %s\n", e.what());
    return 1;
  }
}
