#include "serve/run_publisher.h"

#include <algorithm>
#include <chrono>
#include <exception>
#include <map>
#include <nlohmann/json.hpp>
#include <utility>

#include "nodes/compress/progressive_mesh.h"
#include "runtime/error.h"
#include "runtime/tracing.h"

namespace meshflow::serve {

RunPublisher::RunPublisher(Server& server, std::string source, compress::CompressConfig compress,
                           double encoder_duty)
    : server_(server),
      source_(std::move(source)),
      compress_(std::move(compress)),
      encoder_duty_(std::clamp(encoder_duty, 0.01, 1.0)),
      started_s_(monotonic_seconds()) {
  encoder_ = std::thread([this] { encoder_loop(); });
}

RunPublisher::~RunPublisher() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  encoder_.join();
}

void RunPublisher::frame(const Frame& f, bool with_mesh, MeshCoding coding) {
  publish_frame_stats(f.source_index, f.ok(), f.timings, f.mesh.vertices.size(),
                      f.mesh.triangles.size());
  if (!with_mesh || !f.ok() || f.mesh.triangles.empty()) return;
  Offer o;
  o.coding = coding;
  if (!f.compressed.empty())
    o.encoded = f.compressed;
  else
    o.mesh = f.mesh;
  o.origin = f.origin;
  offer(std::move(o));
}

void RunPublisher::frame(const LiveResult& r) {
  publish_frame_stats(r.seq, r.ok, r.timings, r.mesh.vertices.size(), r.mesh.triangles.size());
  if (!r.ok || r.mesh.triangles.empty()) return;
  Offer o;
  if (!r.compressed.empty())
    o.encoded = r.compressed;
  else
    o.mesh = r.mesh;
  offer(std::move(o));
}

void RunPublisher::result(TriangleMesh mesh, const Eigen::Vector3d& origin, MeshCoding coding,
                          std::vector<unsigned char> encoded) {
  if (mesh.triangles.empty() && encoded.empty()) return;
  Offer o;
  o.mesh = std::move(mesh);
  o.origin = origin;
  o.coding = coding;
  o.encoded = std::move(encoded);
  offer(std::move(o));
}

void RunPublisher::offer(Offer o) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (slot_) ++counts_.meshes_replaced;
    slot_ = std::move(o);
    ++counts_.meshes_offered;
  }
  changed_.notify_all();
}

void RunPublisher::publish_frame_stats(std::uint64_t index, bool ok,
                                       const std::vector<StageRecord>& timings,
                                       std::size_t vertices, std::size_t triangles) {
  std::map<std::string, double> stages;  // a stage may record more than once (steps)
  for (const StageRecord& r : timings) stages[r.stage] += 1e3 * r.duration_s();
  RunPublisherCounts c;
  const double now = monotonic_seconds();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++counts_.frames;
    c = counts_;
    last_frame_s_ = now;
  }
  const double elapsed = now - started_s_;
  nlohmann::json doc = {
      {"type", "stats"},
      {"source", source_},
      {"frame", index},
      {"ok", ok},
      {"frames", c.frames},
      {"frames_per_second", elapsed > 0.0 ? static_cast<double>(c.frames) / elapsed : 0.0},
      {"stages_ms", stages},
      {"vertices", vertices},
      {"triangles", triangles},
      {"meshes_replaced", c.meshes_replaced}};
  server_.publish_stats(doc.dump());
}

void RunPublisher::finish() {
  std::unique_lock<std::mutex> lock(mutex_);
  flushing_ = true;
  changed_.notify_all();
  changed_.wait(lock, [this] { return !slot_ && !encoding_; });
  const RunPublisherCounts c = counts_;
  const double wall = (c.frames > 0 ? last_frame_s_ : monotonic_seconds()) - started_s_;
  lock.unlock();
  const nlohmann::json doc = {
      {"type", "stats"},
      {"source", source_},
      {"state", "finished"},
      {"frames", c.frames},
      {"wall_s", wall},
      {"frames_per_second", wall > 0.0 ? static_cast<double>(c.frames) / wall : 0.0},
      {"meshes_published", c.meshes_encoded},
      {"meshes_replaced", c.meshes_replaced}};
  server_.publish_stats(doc.dump());
  server_.finish();
}

RunPublisherCounts RunPublisher::counts() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return counts_;
}

bool RunPublisher::viewer_wants_mesh() const { return server_.stats().clients_ready_for_mesh > 0; }

void RunPublisher::encoder_loop() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    // A viewer's readiness (Server::stats()) and the duty cycle's pause are polled every 20 ms:
    // a viewer that connects, or finishes taking a mesh, gets the newest one.
    const auto ready = [this] {
      return slot_ && (flushing_ || (monotonic_seconds() >= next_encode_s_ && viewer_wants_mesh()));
    };
    changed_.wait_for(lock, std::chrono::milliseconds(20), [&] { return stop_ || ready(); });
    if (stop_) return;
    if (!ready()) continue;
    Offer o = std::move(*slot_);
    slot_.reset();
    encoding_ = true;
    lock.unlock();
    const double t0 = monotonic_seconds();
    bool published = false;
    try {
      compress::CompressConfig config = compress_;
      config.origin_offset = o.origin;
      const bool progressive = o.coding == MeshCoding::kProgressive;
      if (o.encoded.empty())
        o.encoded = progressive ? compress::compress_progressive(o.mesh, config)
                                : compress::compress_mesh(o.mesh, config);
      // A progressive mesh goes with its single-rate image: a fast link gets the whole mesh
      // sooner that way (Server::publish_mesh()).
      std::vector<unsigned char> single;
      if (progressive && !o.mesh.triangles.empty())
        single = compress::compress_mesh(o.mesh, config);
      server_.publish_mesh(std::move(o.encoded), std::move(single));
      published = true;
    } catch (const std::exception&) {
      // A mesh the codec refuses (or memory for it) is not shown; the run goes on (counted).
    }
    const double t1 = monotonic_seconds();
    lock.lock();
    encoding_ = false;
    next_encode_s_ = t1 + (t1 - t0) * (1.0 / encoder_duty_ - 1.0);
    (published ? counts_.meshes_encoded : counts_.encode_errors) += 1;
    changed_.notify_all();
  }
}

}  // namespace meshflow::serve
