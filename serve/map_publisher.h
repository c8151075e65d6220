#pragma once
// A growing fused map sent to viewers block by block (Server::publish_blocks): after an
// integration, the blocks whose piece of the surface changed are re-meshed by an incremental
// mesher of the publisher's own (TsdfMesher::update; the run's mesher and files are untouched),
// copied, and coded on the publisher's thread, each with meshflow's codec. A viewer that already
// holds the other blocks is sent only the changed ones.
//
// A block's payload (little-endian): u16 s, then s pairs (u16 vertex, u16 edge), then the
// block's piece as a single-rate .mfc image (world coordinates, colours, no normals). `vertex`
// numbers the decoded vertices; `edge` = ((lx * 9 + ly) * 9 + lz) * 3 + axis names the grid
// edge the vertex lies on, (lx, ly, lz) its lower voxel relative to the block's first voxel
// (0 .. 8). Only vertices on edges a neighbouring block shares are listed (a coordinate other
// than the axis at 0 or 8); a receiver welds listed vertices with the same global edge
// (block * 8 + l, axis) and gets the vertices and triangles of TsdfMesher::extract().

#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "nodes/compress/compressed_mesh.h"
#include "nodes/fusion/tsdf_mesher.h"
#include "nodes/fusion/tsdf_volume.h"
#include "serve/server.h"

namespace meshflow::serve {

/// A frame integrated into the map: its number and when it entered the graph
/// (Frame::seq, Frame::submitted_s: monotonic_seconds()).
struct IntegratedFrame {
  std::uint64_t seq = 0;
  double entered_s = 0.0;
};

struct MapPublisherCounts {
  std::uint64_t updates = 0;          ///< re-meshings of the changed blocks
  std::uint64_t updates_skipped = 0;  ///< integrations passed by (no viewer, coder busy, too soon)
  std::uint64_t blocks = 0;           ///< block payloads published (removals included)
  std::uint64_t encode_errors = 0;    ///< pieces the codec refused (sent as removed)
};

/// The payload of one block's piece (the format above): `coords` the block's coordinates, its
/// piece as TsdfMesher made it, `config` the codec's settings (quantisation step). An empty
/// piece gives an empty payload. Throws meshflow::Error when the codec refuses the piece.
std::string encode_block_payload(const Eigen::Vector3i& coords, const TsdfMesher::BlockMesh& piece,
                                 const compress::CompressConfig& config);

class MapPublisher {
 public:
  /// Publishes to `server` (which must outlive this) the blocks of a map of `voxel_size` metres,
  /// meshed with `min_weight` as the run's mesher (FusionConfig::min_weight); positions are
  /// quantised to voxel_size / 64. Updates come at most every `min_interval_s` seconds.
  MapPublisher(Server& server, float voxel_size, float min_weight, double min_interval_s = 0.2);
  /// Stops the coder thread (a batch not yet coded is dropped).
  ~MapPublisher();
  MapPublisher(const MapPublisher&) = delete;
  MapPublisher& operator=(const MapPublisher&) = delete;

  /// After an integration, from the integration node (FusionPipeline's observer), with the
  /// integrated frame's camera centre `sensor` (world metres): when a viewer is connected, the
  /// coder is idle and min_interval_s has passed, re-meshes the changed blocks and hands copies
  /// of their pieces to the coder; otherwise returns at once. The blocks go to each viewer
  /// nearest the newest `sensor` first (Server::publish_blocks). Its cost, held against the
  /// next integration: O(blocks) to find the changed ones + O(their cells).
  ///
  /// The live map's latency: `frame`, when given, is listed in the `shown` message
  /// (Server::publish_blocks) of the first update after it, which each viewer gets once it has
  /// been sent that update's blocks: {"type":"map_shown","frames":[[seq, entered_ms], ...],
  /// "meshed_ms":M,"published_ms":P}, times in milliseconds since the Unix epoch (this machine's
  /// clock, as a browser's performance.timeOrigin + now()): entered = Frame::submitted_s, meshed
  /// = when the update began re-meshing, published = when its blocks were coded. Frames
  /// integrated while no viewer is connected are listed nowhere.
  void integrated(const TsdfMap& map, const Eigen::Vector3f& sensor,
                  std::optional<IntegratedFrame> frame = std::nullopt);
  /// After the run (no integration running): publishes every block changed since the last
  /// update, viewers or not (nearest the last sensor position first), and returns when they are
  /// published.
  void finish(const TsdfMap& map);

  MapPublisherCounts counts() const;

 private:
  struct Piece {
    Eigen::Vector3i coords;
    TsdfMesher::BlockMesh mesh;
  };
  /// `sensor` (world metres) in block units (serve/block_order.h).
  BlockPoint block_point(const Eigen::Vector3f& sensor) const;
  void update(const TsdfMap& map);
  /// The "frames" of a map_shown message for `frames`, and its meshed_ms (epoch ms of `now_s`,
  /// monotonic_seconds()).
  static std::string shown_message_start(const std::vector<IntegratedFrame>& frames, double now_s);
  void coder_loop();

  Server& server_;
  float block_side_m_;  // a block's edge, metres (8 voxels)
  compress::CompressConfig config_;
  double min_interval_s_;
  double last_update_s_ = -1e300;
  TsdfMesher mesher_;                    // the integration node's (or finish()'s) only
  BlockPoint focus_{0.0, 0.0, 0.0};      // the newest sensor position (integration node only)
  std::vector<IntegratedFrame> frames_;  // integrated since the last update (integration node)

  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<Piece> batch_;               // handed to the coder
  BlockPoint batch_focus_{0.0, 0.0, 0.0};  // the sensor position when the batch was made
  std::string batch_shown_;                // the start of the batch's map_shown message ("": none)
  bool batch_ready_ = false;               // batch_ and batch_shown_ wait for the coder
  bool coding_ = false;
  bool stop_ = false;
  MapPublisherCounts counts_;
  std::thread coder_;
};

}  // namespace meshflow::serve
