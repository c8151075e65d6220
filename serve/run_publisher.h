#pragma once
// The sink between a running pipeline and the server (serve/server.h): each delivered frame's
// stage timings, counts and frame rate go out as a small JSON message, and meshes in meshflow's
// codec. Encoding runs on a thread of its own with a slot for the newest mesh only: the graph's
// sink thread only copies a mesh into the slot (replacing one not yet encoded, counted), so a
// run never waits on the encoder or the network. Meshes are encoded only while a viewer is
// ready for one (connected, its last mesh sent: a viewer that stopped reading costs no encoding)
// and the encoder has kept to its duty cycle (busy at most `encoder_duty` of the time, so that it
// takes at most that share of one core from the pipeline), except the last one (finish()), so a
// viewer that comes later sees the result.
//
// Stats message: {"type":"stats","source":S,"frame":I,"ok":B,"frames":N,
//   "frames_per_second":R,"stages_ms":{stage:ms},"vertices":V,"triangles":T,
//   "meshes_replaced":D}; from finish(): {"type":"stats","source":S,"state":"finished",
//   "frames":N,"wall_s":W (to the last frame),"frames_per_second":R (over it),
//   "meshes_published":P,"meshes_replaced":D}.

#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "graph/frame.h"
#include "graph/live_pipeline.h"
#include "nodes/compress/compressed_mesh.h"
#include "runtime/triangle_mesh.h"
#include "serve/server.h"

namespace meshflow::serve {

/// How an offered mesh is coded: single-rate (Edgebreaker: fastest to encode, shown when
/// complete; per-frame meshes) or progressive (base mesh first; a run's final mesh).
enum class MeshCoding { kSingleRate, kProgressive };

struct RunPublisherCounts {
  std::uint64_t frames = 0;           ///< frames reported (failed included)
  std::uint64_t meshes_offered = 0;   ///< meshes handed to the slot
  std::uint64_t meshes_encoded = 0;   ///< meshes encoded and published
  std::uint64_t meshes_replaced = 0;  ///< replaced in the slot before they were encoded
  std::uint64_t encode_errors = 0;    ///< meshes the codec refused (non-finite positions, ...)
};

class RunPublisher {
 public:
  /// Publishes to `server` (which must outlive this), naming the run `source` in the stats
  /// ("meshflow run", ...). `compress` sets the codec's quantisation and progressive settings
  /// (origin_offset is set per mesh). After an encoding of t seconds the next starts no sooner
  /// than t * (1 / encoder_duty - 1) later (`encoder_duty` in [0.01, 1]). Starts the encoder
  /// thread.
  RunPublisher(Server& server, std::string source, compress::CompressConfig compress = {},
               double encoder_duty = 0.25);
  /// Stops the encoder thread; a mesh not yet encoded is dropped.
  ~RunPublisher();
  RunPublisher(const RunPublisher&) = delete;
  RunPublisher& operator=(const RunPublisher&) = delete;

  /// A delivered frame (call from the sink, one at a time): publishes its stats and, with
  /// `with_mesh` and a mesh, offers it (its Frame::compressed image when it has one, else a copy
  /// of the mesh, coded `coding` in world coordinates). O(mesh) copy; never waits on the network.
  void frame(const Frame& f, bool with_mesh, MeshCoding coding = MeshCoding::kSingleRate);
  /// The same for a frame of the embedding API (graph/live_pipeline.h).
  void frame(const LiveResult& result);
  /// A run's result (its final mesh, `origin` added as Frame::origin says; `encoded` a ready
  /// .mfc image of it, or empty): offered like a frame's mesh, coded `coding`.
  void result(TriangleMesh mesh, const Eigen::Vector3d& origin,
              MeshCoding coding = MeshCoding::kProgressive,
              std::vector<unsigned char> encoded = {});
  /// The run is over: encodes and publishes the newest offered mesh (viewers or not), publishes
  /// the final stats and tells the viewers (Server::finish()). Blocks for that one encoding.
  void finish();

  RunPublisherCounts counts() const;

 private:
  struct Offer {
    TriangleMesh mesh;
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    MeshCoding coding = MeshCoding::kSingleRate;
    std::vector<unsigned char> encoded;
  };
  void offer(Offer offer);
  void publish_frame_stats(std::uint64_t index, bool ok, const std::vector<StageRecord>& timings,
                           std::size_t vertices, std::size_t triangles);
  void encoder_loop();
  bool viewer_wants_mesh() const;

  Server& server_;
  std::string source_;
  compress::CompressConfig compress_;
  double encoder_duty_;
  double started_s_ = 0.0;
  double next_encode_s_ = 0.0;  // the duty cycle: no encoding before (under mutex_)
  double last_frame_s_ = 0.0;   // when the last frame was reported (under mutex_)

  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::optional<Offer> slot_;
  bool encoding_ = false;
  bool flushing_ = false;  // finish(): encode even without viewers
  bool stop_ = false;
  RunPublisherCounts counts_;
  std::thread encoder_;
};

}  // namespace meshflow::serve
