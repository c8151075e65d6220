#include "serve/map_publisher.h"

#include <chrono>
#include <cstdio>
#include <exception>
#include <nlohmann/json.hpp>
#include <utility>

#include "runtime/error.h"
#include "runtime/tracing.h"
#include "runtime/voxel_key.h"

namespace meshflow::serve {

namespace {

void put_u16(std::string& out, std::uint32_t v) {
  out.push_back(static_cast<char>(v & 0xff));
  out.push_back(static_cast<char>((v >> 8) & 0xff));
}

}  // namespace

std::string encode_block_payload(const Eigen::Vector3i& coords, const TsdfMesher::BlockMesh& piece,
                                 const compress::CompressConfig& config) {
  if (piece.triangles.empty()) return {};
  TriangleMesh mesh;
  mesh.vertices = piece.vertices;
  mesh.colors = piece.colors;
  mesh.triangles = piece.triangles;
  compress::CompressReport report;
  const std::vector<unsigned char> mfc = compress::compress_mesh(mesh, config, &report);
  const Eigen::Vector3i first = coords * kTsdfBlockSide;
  std::string shared;
  std::uint32_t count = 0;
  for (std::size_t k = 0; k < report.vertex_order.size(); ++k) {
    const std::uint64_t key = piece.edge_keys[report.vertex_order[k]];
    const int axis = static_cast<int>(key & 3u);
    const Eigen::Vector3i l = unpack_key(key >> 2) - first;
    bool on_face = false;
    for (int a = 0; a < 3; ++a)
      if (a != axis && (l[a] == 0 || l[a] == kTsdfBlockSide)) on_face = true;
    if (!on_face) continue;
    put_u16(shared, static_cast<std::uint32_t>(k));
    put_u16(shared, static_cast<std::uint32_t>(((l.x() * 9 + l.y()) * 9 + l.z()) * 3 + axis));
    ++count;
  }
  std::string payload;
  put_u16(payload, count);
  payload += shared;
  payload.append(reinterpret_cast<const char*>(mfc.data()), mfc.size());
  return payload;
}

MapPublisher::MapPublisher(Server& server, float voxel_size, float min_weight,
                           double min_interval_s)
    : server_(server),
      block_side_m_(voxel_size * static_cast<float>(kTsdfBlockSide)),
      min_interval_s_(min_interval_s),
      mesher_(min_weight) {
  config_.step = static_cast<double>(voxel_size) / 64.0;
  config_.normals = false;  // the pieces have none; the page computes them
  coder_ = std::thread([this] { coder_loop(); });
}

MapPublisher::~MapPublisher() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  coder_.join();
}

BlockPoint MapPublisher::block_point(const Eigen::Vector3f& sensor) const {
  return {static_cast<double>(sensor.x() / block_side_m_),
          static_cast<double>(sensor.y() / block_side_m_),
          static_cast<double>(sensor.z() / block_side_m_)};
}

namespace {

// Milliseconds since the Unix epoch of `monotonic_s` (monotonic_seconds()), by this machine's
// clock now.
double map_epoch_ms(double monotonic_s) {
  const double epoch_now_s =
      std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  return 1e3 * (epoch_now_s - monotonic_seconds() + monotonic_s);
}

}  // namespace

void MapPublisher::integrated(const TsdfMap& map, const Eigen::Vector3f& sensor,
                              std::optional<IntegratedFrame> frame) {
  if (sensor.allFinite()) focus_ = block_point(sensor);
  const double now = monotonic_seconds();
  if (server_.stats().clients == 0) {  // nobody to show it to
    frames_.clear();
    std::lock_guard<std::mutex> lock(mutex_);
    ++counts_.updates_skipped;
    return;
  }
  if (frame) frames_.push_back(*frame);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (coding_ || batch_ready_ || now - last_update_s_ < min_interval_s_) {
      ++counts_.updates_skipped;
      return;
    }
  }
  last_update_s_ = now;
  update(map);
}

void MapPublisher::finish(const TsdfMap& map) {
  {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [this] { return !batch_ready_ && !coding_; });
  }
  update(map);
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [this] { return !batch_ready_ && !coding_; });
}

std::string MapPublisher::shown_message_start(const std::vector<IntegratedFrame>& frames,
                                              double now_s) {
  nlohmann::json list = nlohmann::json::array();
  for (const IntegratedFrame& f : frames) list.push_back({f.seq, map_epoch_ms(f.entered_s)});
  std::string text = nlohmann::json{{"type", "map_shown"}, {"frames", list}}.dump();
  text.pop_back();  // the coder adds the published time and the closing brace
  char meshed[64];
  std::snprintf(meshed, sizeof meshed, ",\"meshed_ms\":%.3f", map_epoch_ms(now_s));
  return text + meshed;
}

void MapPublisher::update(const TsdfMap& map) {
  const double now = monotonic_seconds();
  std::vector<Piece> pieces;
  for (const VoxelKey key : mesher_.update(map)) {
    const TsdfMesher::BlockMesh* piece = mesher_.block_mesh(key);
    pieces.push_back({unpack_key(key), piece != nullptr ? *piece : TsdfMesher::BlockMesh{}});
  }
  std::string shown = frames_.empty() ? std::string() : shown_message_start(frames_, now);
  frames_.clear();
  std::lock_guard<std::mutex> lock(mutex_);
  ++counts_.updates;
  if (pieces.empty() && shown.empty()) return;
  batch_ = std::move(pieces);
  batch_shown_ = std::move(shown);
  batch_focus_ = focus_;
  batch_ready_ = true;
  changed_.notify_all();
}

MapPublisherCounts MapPublisher::counts() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return counts_;
}

void MapPublisher::coder_loop() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    changed_.wait(lock, [this] { return stop_ || batch_ready_; });
    if (stop_) return;
    std::vector<Piece> pieces = std::move(batch_);
    batch_.clear();
    std::string shown = std::move(batch_shown_);
    batch_shown_.clear();
    batch_ready_ = false;
    const BlockPoint focus = batch_focus_;
    coding_ = true;
    lock.unlock();
    std::vector<MapBlock> blocks;
    std::uint64_t errors = 0;
    for (const Piece& p : pieces) {
      MapBlock b{p.coords.x(), p.coords.y(), p.coords.z(), nullptr};
      try {
        b.payload =
            std::make_shared<const std::string>(encode_block_payload(p.coords, p.mesh, config_));
      } catch (const std::exception&) {  // the codec's refusal, or memory for the block
        b.payload = std::make_shared<const std::string>();  // shown as removed
        ++errors;
      }
      blocks.push_back(std::move(b));
    }
    const std::size_t published = blocks.size();
    if (!shown.empty()) {
      char published_at[64];
      std::snprintf(published_at, sizeof published_at, ",\"published_ms\":%.3f}",
                    map_epoch_ms(monotonic_seconds()));
      shown += published_at;
    }
    server_.publish_blocks(std::move(blocks), focus, std::move(shown));
    lock.lock();
    coding_ = false;
    counts_.blocks += published;
    counts_.encode_errors += errors;
    changed_.notify_all();
  }
}

}  // namespace meshflow::serve
