#pragma once
// meshflow's HTTP + WebSocket server (Boost.Beast over Boost.Asio): it serves a fixed set of
// in-memory resources (the viewer page) and streams what the rest of meshflow publishes (meshes
// in meshflow's own codec, small JSON messages) to every connected browser.
//
// Safe by default:
//   - binds 127.0.0.1 unless the config names another host;
//   - read-only: a request's path is only looked up in `ServerConfig::resources` (fixed when
//     the server starts); nothing a client sends reaches the filesystem or changes the run;
//   - a bounded number of WebSocket clients (others get HTTP 503) and of HTTP connections;
//   - each client's send queue holds only the newest mesh and the newest stats: a published
//     mesh replaces the unsent frames of older ones (counted as dropped), so a slow or stalled
//     client costs memory for one mesh (shared by all clients), never a blocked producer; a
//     fused map's blocks wait for the client's acknowledgement (flow control), each block at
//     most once, so a client behind costs at most the map's block keys;
//   - every client message is checked: larger than `max_client_message_bytes` (Beast closes
//     with 1009), faster than the rate limit, binary, or not a JSON object {"type": "hello" |
//     "ping"} or a valid {"type": "map_ack"} (serve/client_message.h) closes the connection
//     (1008 policy / 1003 unsupported data).
//
// Wire protocol, server to client (see web/viewer.js):
//   text   {"type":"mesh","id":N,"kind":"progressive"|"edgebreaker","bytes":B,
//           "base_end":E,"packet_ends":[...],"vertices":V,"triangles":T,"chunks":C,
//           "refine":"packets"|"single_rate","single_rate_bytes":S}
//   binary u32 id, u32 offset (little-endian), then bytes [offset, offset + n) of mesh N's .mfc
//          image; chunks of one mesh arrive in order, the first holds the base mesh. With
//          "refine":"single_rate" only the base chunk of the progressive image comes, then
//          the mesh's single-rate image (S bytes) in chunks whose id is N | 0x80000000
//   binary u32 0 (a block batch: mesh ids start at 1), u32 count, then count blocks of a fused
//          map, each i32 x, y, z (block coordinates), u32 n and n bytes of its payload
//          (publish_blocks(); serve/map_publisher.h says what a payload holds; n = 0: the block
//          has no surface any more)
//   text   the JSON objects given to publish_stats() (they carry their own "type")
//   text   a publish_blocks() publication's `shown` message, after its last block (only the
//          newest of those due at once: it stands for the older ones)
//   text   {"type":"map_round","round":N} (N = 1, 2, ...) after the last block batch of a round:
//          the blocks that waited when the round began. The client answers
//          {"type":"map_ack","round":N} once it has applied and drawn them; the next round waits
//          for that (ServerConfig::map_rounds_in_flight). An acknowledgement out of order or of
//          a round not sent closes the connection (1008)
//   text   {"type":"end"} after finish(): the producer is done and the client holds everything
//          it published (sent last, after the client's queue has drained)
//
// Threads: the server runs its own I/O thread. Every public member is thread-safe and returns
// without waiting for the network.

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "serve/block_order.h"

namespace meshflow::serve {

/// One resource the server answers GET / HEAD with.
struct StaticResource {
  std::string content_type;                 ///< e.g. "text/html; charset=utf-8"
  std::shared_ptr<const std::string> body;  ///< the bytes (shared, never copied per client)
};

struct ServerConfig {
  /// The address to listen on; the default is the loopback interface only.
  std::string host = "127.0.0.1";
  /// 0: any free port (Server::port() tells which).
  std::uint16_t port = 0;
  /// WebSocket clients at once; more get HTTP 503.
  std::size_t max_clients = 8;
  /// Open HTTP connections at once (page loads included); more are closed at accept.
  std::size_t max_connections = 64;
  /// A client message larger than this closes the connection (close code 1009).
  std::size_t max_client_message_bytes = 1024;
  /// Token bucket of client messages: `client_message_burst` at once, refilled at this rate.
  double client_messages_per_second = 10.0;
  double client_message_burst = 20.0;
  /// The resources, by request path ("/", "/viewer.js", ...). Nothing else is served.
  std::map<std::string, StaticResource> resources;
  /// The path of the WebSocket endpoint.
  std::string websocket_path = "/ws";
  /// Caps each client's bandwidth, megabits per second (0: no cap): whole frames are sent no
  /// faster than this, to feel a narrow link or to spare a robot's uplink. Frames waiting for
  /// the cap are dropped for newer ones like those of a slow client.
  double client_megabits_per_second = 0.0;
  /// Bytes of one mesh per binary frame (cut at progressive packet boundaries when possible).
  std::size_t chunk_bytes = 64 * 1024;
  /// A progressive mesh published with its single-rate image (publish_mesh()) is refined by
  /// that image instead of the vertex-split packets when the image is the smaller and takes at
  /// most this long at the bandwidth cap (always without a cap; 0: never): the whole mesh
  /// arrives sooner and decodes faster, but nothing between the base and the full mesh is shown.
  double single_rate_within_s = 1.0;
  /// Flow control of a fused map's blocks: a viewer is sent the blocks waiting for it in
  /// rounds, each closed by {"type":"map_round","round":N}; a new round starts only while
  /// fewer than this many rounds wait for the viewer's {"type":"map_ack","round":N} (at least
  /// 1). Meanwhile changed blocks wait, each once with its newest payload.
  std::size_t map_rounds_in_flight = 1;
};

/// One block of a fused map as published: its block coordinates and payload (empty: the block
/// has no surface any more).
struct MapBlock {
  std::int32_t x = 0, y = 0, z = 0;
  std::shared_ptr<const std::string> payload;
};

/// Counters since the server started.
struct ServerStats {
  std::size_t clients = 0;                       ///< WebSocket clients connected now
  std::uint64_t clients_accepted = 0;            ///< WebSocket handshakes completed
  std::uint64_t clients_refused = 0;             ///< upgrades refused (client limit)
  std::uint64_t clients_closed_bad_message = 0;  ///< closed for a malformed/oversized/fast message
  std::uint64_t frames_sent = 0;                 ///< WebSocket frames written
  std::uint64_t ends_sent = 0;  ///< {"type":"end"} messages written (one per client after finish())
  /// Clients connected now with no mesh frame waiting or being written: those a new mesh
  /// would reach now (a stalled client keeps its last mesh's frame and is not counted).
  std::size_t clients_ready_for_mesh = 0;
  std::uint64_t frames_dropped = 0;  ///< frames replaced by newer ones before they were sent
  std::uint64_t bytes_sent = 0;      ///< WebSocket payload bytes written
  std::uint64_t http_requests = 0;   ///< HTTP requests answered
  std::uint64_t meshes_published = 0;
  /// Publications replaced by newer ones before the I/O thread took them (never sent).
  std::uint64_t publications_replaced = 0;
  /// The longest any client's send queue has been, in frames (the frame being written
  /// included): at most one mesh's frames and one stats message, however slow the client.
  std::size_t max_client_queue_frames = 0;
  std::uint64_t blocks_published = 0;  ///< blocks handed to publish_blocks()
  std::uint64_t blocks_sent = 0;       ///< blocks written to clients (in batches)
  /// Blocks published again while a client still waited for the block: sent once, the newest.
  std::uint64_t blocks_superseded = 0;
  /// The most blocks any client has waited for at once (at most the map's blocks).
  std::size_t max_client_pending_blocks = 0;
  std::uint64_t map_rounds_sent = 0;          ///< {"type":"map_round"} messages queued
  std::uint64_t map_rounds_acknowledged = 0;  ///< valid {"type":"map_ack"} messages received
  /// publish_blocks()' `shown` messages a newer one stood for (a viewer behind), never sent.
  std::uint64_t shown_superseded = 0;
};

/// The server. Construction binds and starts the I/O thread (throws meshflow::Error when the
/// address cannot be bound); destruction closes every connection and joins the thread.
class Server {
 public:
  explicit Server(ServerConfig config);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  /// The bound address and port.
  const std::string& host() const;
  std::uint16_t port() const;
  /// "http://HOST:PORT/".
  std::string url() const;

  /// Publishes a mesh as a .mfc image (compressed_mesh.h; progressive images are cut into a
  /// base chunk and chunks of whole split packets). Every client gets it, new clients too;
  /// frames of older meshes not yet sent are dropped. `single_rate`, when given with a
  /// progressive `mfc`, is the same mesh's single-rate image: it follows the base instead of
  /// the packets when ServerConfig::single_rate_within_s says so. Throws meshflow::Error if
  /// `mfc` is not a valid .mfc image, or `single_rate` not a single-rate image of as many
  /// vertices and triangles (headers and, when progressive, the packet layout are read here,
  /// on the caller's thread: O(base mesh)). Does not wait for the network.
  void publish_mesh(std::vector<unsigned char> mfc, std::vector<unsigned char> single_rate = {});
  /// Publishes a JSON object text (sent as is; give it a "type"). The newest replaces unsent
  /// older ones; new clients get the newest. Does not wait for the network.
  void publish_stats(std::string json);
  /// Publishes changed blocks of a fused map. Every client is sent each block that changed since
  /// it was last sent that block, the newest payload only (a block changed twice before a slow
  /// client took it goes once), in batches of about `chunk_bytes` after its stats and mesh
  /// frames; a new client gets every block. The blocks a client waits for go nearest first to
  /// `focus`, the newest sensor position in block units (serve/block_order.h; the last focus
  /// given stays, the origin until one is), ties by block coordinates. Memory: the newest
  /// payload per block (shared by all clients) and per client the keys of the blocks it waits
  /// for. Does not wait for the network; O(b log b) per client for b waiting blocks.
  ///
  /// `shown`, when not empty, is a text message (a JSON object with its own "type") sent to each
  /// client connected now once it has been sent every block of this publication (or a newer
  /// payload of it), and the `shown` messages of earlier publications: right after the batch
  /// that held the last of them, so a client that has applied the frames before it holds what
  /// the publication describes (the live map's latency: serve/map_publisher.h). Never dropped;
  /// O(log b) per block sent for the bookkeeping.
  void publish_blocks(std::vector<MapBlock> blocks, std::optional<BlockPoint> focus = std::nullopt,
                      std::string shown = {});
  /// Tells the server nothing more will be published (a run is over): each client, present or
  /// future, gets {"type":"end"} after what is queued for it. Does not wait for the network.
  void finish();

  ServerStats stats() const;

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace meshflow::serve
