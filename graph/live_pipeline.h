#pragma once
// The embedding API: a reconstruction pipeline that an application's own sensor loop pushes
// frames into, one at a time, and that hands each finished mesh to a callback. push() never
// blocks on reconstruction work: it either queues the frame, or (by policy) drops the oldest
// waiting frame or refuses the new one.
//
//   LivePipeline live(config, [](LiveResult& r) { use(r.mesh); });
//   for (;;) live.push(camera.grab());   // returns at once
//   live.flush();                        // everything accepted has been delivered

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "graph/frame.h"
#include "graph/reconstruction_config.h"

namespace meshflow {

enum class LivePolicy {
  kQueue,    ///< keep every accepted frame; push() refuses frames while the queue is full
  kRealtime  ///< a full queue drops its oldest waiting frame for the new one: latency bounded
};

struct LiveConfig {
  ReconstructionConfig reconstruction;
  /// Threads of the pipeline's own task arena (frames and the parallel loops inside each
  /// stage share them); 0 = one per core.
  int threads = 0;
  std::size_t frames_in_flight = 2;  ///< frames being reconstructed at once (>= 1)
  std::size_t max_waiting = 2;       ///< frames queued behind them (>= 1)
  LivePolicy policy = LivePolicy::kRealtime;
  /// Triangulate each depth map, or organized point cloud, directly
  /// (reconstruction.triangulation: naive or restricted quadtree, optional QEM) instead of the
  /// volumetric stages; unorganized clouds then fail with a message saying so.
  bool triangulate_depth_maps = false;
};

/// One finished frame, as the callback receives it (the callback may move the mesh out).
struct LiveResult {
  std::uint64_t seq = 0;  ///< what push() returned for this frame
  bool ok = false;
  std::string error;         ///< when !ok: what went wrong, naming the frame and the field
  std::string failed_stage;  ///< when !ok
  TriangleMesh mesh;
  /// With reconstruction.compression set: the mesh as compressed-mesh bytes (.mfc, world
  /// coordinates), ready to send; decode with compress::decompress_mesh().
  std::vector<unsigned char> compressed;
  std::vector<StageRecord> timings;  ///< per stage, monotonic seconds
  double latency_s = 0.0;            ///< from push() to the callback
};

struct LiveStats {
  std::uint64_t pushed = 0;               ///< push() calls while open
  std::uint64_t rejected = 0;             ///< kQueue: refused because the queue was full
  std::uint64_t dropped = 0;              ///< kRealtime: accepted, then displaced while waiting
  std::uint64_t delivered = 0;            ///< callbacks made (failed frames included)
  std::uint64_t failed = 0;               ///< delivered with ok == false
  std::uint64_t callback_exceptions = 0;  ///< callbacks that threw (caught and counted)
  std::size_t waiting = 0;                ///< queued now
  std::size_t in_flight = 0;              ///< being reconstructed now
  /// Latency percentiles (seconds) over the last 4096 delivered frames; 0 before the first.
  double latency_p50_s = 0.0, latency_p95_s = 0.0, latency_p99_s = 0.0;
};

class LivePipeline {
 public:
  /// Called once per accepted, undropped frame, in push order, never concurrently with itself,
  /// on one of the pipeline's threads. It may push(); it must not call flush() or destroy the
  /// pipeline, and should not throw (exceptions are caught and counted).
  using Callback = std::function<void(LiveResult&)>;

  enum class PushStatus {
    kAccepted,               ///< queued or started
    kAcceptedDroppedOldest,  ///< kRealtime: queued; the oldest waiting frame was dropped
    kRejected,               ///< kQueue: the queue is full (back-pressure); the frame is discarded
  };
  struct Push {
    PushStatus status;
    std::uint64_t seq;  ///< numbers every push() call, 0, 1, 2, ...
  };

  /// Starts the pipeline's threads. Throws meshflow::Error for an empty callback.
  LivePipeline(LiveConfig config, Callback callback);
  /// Stops: frames still waiting are discarded, frames in flight are finished without a
  /// callback; returns when no pipeline thread touches the callback any more. Frames wanted
  /// in full need flush() first.
  ~LivePipeline();
  LivePipeline(const LivePipeline&) = delete;
  LivePipeline& operator=(const LivePipeline&) = delete;

  /// Hands over a frame: a point cloud (metres, world frame; sensor origin if known) or a depth
  /// image with intrinsics and pose. Thread-safe; O(1) apart from moving the frame in; never
  /// waits for reconstruction work.
  Push push(PointCloud cloud, double timestamp_s = 0.0);
  /// The same for a depth image with intrinsics and pose (check_depth_frame() runs in the graph: a
  /// bad frame is delivered failed).
  Push push(DepthFrame frame);

  /// Blocks until every accepted, undropped frame has been delivered. Thread-safe.
  void flush();

  /// Counters and latency percentiles. Thread-safe.
  LiveStats stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace meshflow
