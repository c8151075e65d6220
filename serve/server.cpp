#include "serve/server.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <cstring>
#include <deque>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <thread>
#include <utility>

#include "runtime/error.h"
#include "serve/client_message.h"
#include "serve/mesh_stream.h"

namespace meshflow::serve {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using error_code = boost::system::error_code;

namespace {

/// One frame queued for a client; its bytes are shared by every client.
struct Outgoing {
  enum class Kind { kMesh, kStats, kEnd, kBlocks, kShown, kRound } kind = Kind::kMesh;
  bool binary = false;
  std::shared_ptr<const std::string> data;
};

/// A published mesh, ready to send: its header message and its binary chunks.
struct MeshMessage {
  std::vector<Outgoing> frames;
};

}  // namespace

class WsSession;
class HttpSession;

namespace {

/// {"type":"end"}: queued behind everything else, never dropped (nothing follows it).
Outgoing end_message() {
  static const auto text = std::make_shared<const std::string>(R"({"type":"end"})");
  return {Outgoing::Kind::kEnd, false, text};
}

}  // namespace

class Server::Impl {
 public:
  explicit Impl(ServerConfig config) : config_(std::move(config)), acceptor_(ioc_) {
    asio::ip::address address;
    error_code ec;
    const std::string host = config_.host == "localhost" ? "127.0.0.1" : config_.host;
    address = asio::ip::make_address(host, ec);
    if (ec) throw Error("server", "host", "an IP address or localhost, got \"" + host + "\"");
    const tcp::endpoint endpoint(address, config_.port);
    acceptor_.open(endpoint.protocol(), ec);
    if (!ec) acceptor_.set_option(asio::socket_base::reuse_address(true), ec);
    if (!ec) acceptor_.bind(endpoint, ec);
    if (!ec) acceptor_.listen(asio::socket_base::max_listen_connections, ec);
    if (ec)
      throw Error("server", "address " + host + ":" + std::to_string(config_.port),
                  "an address this machine can listen on (" + ec.message() + ")");
    host_ = acceptor_.local_endpoint().address().to_string();
    port_ = acceptor_.local_endpoint().port();
    do_accept();
    thread_ = std::thread([this] { ioc_.run(); });
  }

  ~Impl() {
    asio::post(ioc_, [this] { shut_down(); });
    thread_.join();
  }

  void do_accept();
  void shut_down();
  void drain();
  bool add_client(const std::shared_ptr<WsSession>& session);
  void remove_client(const std::shared_ptr<WsSession>& session);

  void publish(std::shared_ptr<const MeshMessage> mesh, std::shared_ptr<const std::string> stats,
               bool finish = false, std::vector<MapBlock> blocks = {},
               std::optional<BlockPoint> focus = std::nullopt, std::string shown = {}) {
    std::lock_guard<std::mutex> lock(pending_mutex_);
    if (finish) pending_finish_ = true;
    if (!shown.empty())
      pending_shown_.push_back(std::make_shared<const std::string>(std::move(shown)));
    if (focus) pending_focus_ = focus;
    for (MapBlock& b : blocks) pending_blocks_[BlockKey{b.x, b.y, b.z}] = std::move(b.payload);
    if (mesh && pending_mesh_) ++counters_.publications_replaced;
    if (stats && pending_stats_) ++counters_.publications_replaced;
    if (mesh) pending_mesh_ = std::move(mesh);
    if (stats) pending_stats_ = std::move(stats);
    if (!drain_posted_) {
      drain_posted_ = true;
      asio::post(ioc_, [this] { drain(); });
    }
  }

  ServerConfig config_;
  asio::io_context ioc_{1};
  tcp::acceptor acceptor_;
  std::string host_;
  std::uint16_t port_ = 0;
  std::thread thread_;
  bool stopping_ = false;  // I/O thread only

  // I/O thread only: the clients and what a new one is sent first.
  std::set<std::shared_ptr<WsSession>> clients_;
  std::set<std::shared_ptr<HttpSession>> connections_;
  std::shared_ptr<const MeshMessage> current_mesh_;
  std::shared_ptr<const std::string> current_stats_;
  bool finished_ = false;  // finish() reached the I/O thread: clients get the end message
  std::map<BlockKey, std::shared_ptr<const std::string>> blocks_;  // the newest of each block
  BlockPoint focus_{0.0, 0.0, 0.0};  // the newest sensor position: nearest blocks go first

  // Producers to the I/O thread: the newest unsent publications (older ones are replaced).
  std::mutex pending_mutex_;
  std::shared_ptr<const MeshMessage> pending_mesh_;
  std::shared_ptr<const std::string> pending_stats_;
  bool pending_finish_ = false;
  std::map<BlockKey, std::shared_ptr<const std::string>> pending_blocks_;
  std::optional<BlockPoint> pending_focus_;
  std::vector<std::shared_ptr<const std::string>> pending_shown_;  // publish_blocks()' `shown`
  bool drain_posted_ = false;

  std::atomic<std::uint64_t> mesh_id_{0};
  struct Counters {
    std::atomic<std::size_t> clients{0};
    std::atomic<std::uint64_t> clients_accepted{0}, clients_refused{0}, clients_closed_bad{0},
        frames_sent{0}, frames_dropped{0}, bytes_sent{0}, http_requests{0}, meshes{0},
        publications_replaced{0}, max_client_queue{0}, blocks_published{0}, blocks_sent{0},
        blocks_superseded{0}, max_pending_blocks{0}, ends_sent{0}, map_rounds{0}, map_acks{0},
        shown_superseded{0};
    std::atomic<std::size_t> clients_waiting_for_mesh{0};  // with a mesh frame queued or in flight
  } counters_;
};

/// One WebSocket client: a read loop that validates each message, and a write queue holding
/// only the newest mesh and stats.
class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(tcp::socket socket, Server::Impl& server)
      : ws_(std::move(socket)),
        server_(server),
        tokens_(server.config_.client_message_burst),
        last_refill_(std::chrono::steady_clock::now()) {}

  void run(http::request<http::string_body> request) {
    // Frames are written whole: Nagle's algorithm would only hold a mesh's last, short chunk
    // back until the previous one is acknowledged.
    error_code ignored;
    beast::get_lowest_layer(ws_).socket().set_option(tcp::no_delay(true), ignored);
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.read_message_max(server_.config_.max_client_message_bytes);
    ws_.set_option(websocket::stream_base::decorator(
        [](websocket::response_type& response) { response.set(http::field::server, "meshflow"); }));
    ws_.async_accept(request, beast::bind_front_handler(&WsSession::on_accept, shared_from_this()));
  }

  void enqueue(const Outgoing& frame) {
    if (closing_) return;
    // Stale frames of the same kind (an older mesh, older stats) that have not started are
    // dropped: the queue never holds more than the newest of each.
    if (frame.kind == Outgoing::Kind::kStats || starts_mesh(frame)) {
      auto stale = std::remove_if(queue_.begin(), queue_.end(),
                                  [&](const Outgoing& o) { return o.kind == frame.kind; });
      server_.counters_.frames_dropped += static_cast<std::uint64_t>(queue_.end() - stale);
      queue_.erase(stale, queue_.end());
    }
    queue_.push_back(frame);
    const std::size_t queued = queue_.size() + (writing_ ? 1 : 0);
    if (queued > server_.counters_.max_client_queue) server_.counters_.max_client_queue = queued;
    if (!writing_) write_next();
    note_mesh_pending();
  }

  /// The client is to be sent these blocks (their newest payloads, taken when a batch is cut),
  /// with those it waits for already, nearest to `focus` (block units) first.
  /// `shown`: messages to send once these blocks and those waiting already have been sent.
  void mark_blocks(const std::vector<BlockKey>& keys, const BlockPoint& focus,
                   const std::vector<std::shared_ptr<const std::string>>& shown = {}) {
    if (closing_) return;
    blocks_waiting_.set_focus(focus);
    blocks_later_.set_focus(focus);
    for (const BlockKey& key : keys) {
      if (blocks_waiting_.contains(key) || blocks_later_.contains(key)) {
        ++server_.counters_.blocks_superseded;  // it keeps the earliest generation waiting
        continue;
      }
      // A round being sent keeps its blocks: a block it has sent already waits for the next.
      (round_open_ ? blocks_later_ : blocks_waiting_).push(key);
      block_generation_[key] = generation_;
      ++waiting_by_generation_[generation_];
    }
    const std::size_t pending = blocks_waiting_.size() + blocks_later_.size();
    if (pending > server_.counters_.max_pending_blocks)
      server_.counters_.max_pending_blocks = pending;
    if (!shown.empty()) {
      // The newest message of these publications stands for them all; of those still waiting
      // for blocks, the oldest (due first) and the newest stay: at most two, however far
      // behind the viewer is.
      server_.counters_.shown_superseded += shown.size() - 1;
      shown_.emplace_back(generation_, shown.back());
      if (shown_.size() > 2) {
        shown_.erase(shown_.end() - 2);
        ++server_.counters_.shown_superseded;
      }
      ++generation_;
      queue_shown();
    }
    if (!writing_) write_next();
  }

  void close() {
    if (closing_) return;
    closing_ = true;
    error_code ec;
    beast::get_lowest_layer(ws_).socket().shutdown(tcp::socket::shutdown_both, ec);
    beast::get_lowest_layer(ws_).socket().close(ec);
  }

 private:
  /// The next batch of pending blocks, about chunk_bytes (at least one block), as one frame:
  /// u32 0, u32 count, then per block i32 x, y, z, u32 n, n payload bytes. The batch that
  /// empties the round's blocks closes it: its due `shown` message and {"type":"map_round"}
  /// follow it, and the blocks marked meanwhile make the next round.
  Outgoing block_batch() {
    round_open_ = true;
    std::string frame(8, '\0');
    std::uint32_t count = 0;
    const auto put = [&frame](std::uint32_t v) {
      for (int b = 0; b < 4; ++b) frame.push_back(static_cast<char>(v >> (8 * b)));
    };
    while (!blocks_waiting_.empty() && (count == 0 || frame.size() < server_.config_.chunk_bytes)) {
      const BlockKey key = blocks_waiting_.pop();
      sent_block(key);
      const auto found = server_.blocks_.find(key);
      const std::string empty;
      const std::string& payload =
          found != server_.blocks_.end() && found->second ? *found->second : empty;
      for (std::int32_t c : key) put(static_cast<std::uint32_t>(c));
      put(static_cast<std::uint32_t>(payload.size()));
      frame += payload;
      ++count;
    }
    for (int b = 0; b < 4; ++b)
      frame[static_cast<std::size_t>(4 + b)] = static_cast<char>(count >> (8 * b));
    server_.counters_.blocks_sent += count;
    Outgoing batch{Outgoing::Kind::kBlocks, true,
                   std::make_shared<const std::string>(std::move(frame))};
    queue_shown();  // behind this batch in the queue
    if (blocks_waiting_.empty()) {
      round_open_ = false;
      ++rounds_sent_;
      ++server_.counters_.map_rounds;
      insert_before_end({Outgoing::Kind::kRound, false,
                         std::make_shared<const std::string>(R"({"type":"map_round","round":)" +
                                                             std::to_string(rounds_sent_) + "}")});
      while (!blocks_later_.empty()) blocks_waiting_.push(blocks_later_.pop());
    }
    return batch;
  }

  /// The bookkeeping of the `shown` messages for a block taken from the waiting ones. O(log n).
  void sent_block(const BlockKey& key) {
    const auto found = block_generation_.find(key);
    if (found == block_generation_.end()) return;
    const auto count = waiting_by_generation_.find(found->second);
    if (count != waiting_by_generation_.end() && --count->second == 0)
      waiting_by_generation_.erase(count);
    block_generation_.erase(found);
  }

  /// Queues the newest `shown` message whose publication's blocks have all been taken (a
  /// generation below every waiting block's); it replaces older due ones, queued or not (the
  /// newest frame merged into what was sent stands for them).
  void queue_shown() {
    std::shared_ptr<const std::string> due;
    while (!shown_.empty() && (waiting_by_generation_.empty() ||
                               shown_.front().first < waiting_by_generation_.begin()->first)) {
      if (due) ++server_.counters_.shown_superseded;
      due = shown_.front().second;
      shown_.pop_front();
    }
    if (!due) return;
    const auto stale = std::remove_if(queue_.begin(), queue_.end(), [](const Outgoing& o) {
      return o.kind == Outgoing::Kind::kShown;
    });
    server_.counters_.shown_superseded += static_cast<std::uint64_t>(queue_.end() - stale);
    queue_.erase(stale, queue_.end());
    insert_before_end({Outgoing::Kind::kShown, false, due});
  }

  /// Queues `frame` before the end message, which stays last.
  void insert_before_end(Outgoing frame) {
    const auto end = std::find_if(queue_.begin(), queue_.end(),
                                  [](const Outgoing& o) { return o.kind == Outgoing::Kind::kEnd; });
    queue_.insert(end, std::move(frame));
  }

  static bool starts_mesh(const Outgoing& frame) {
    return frame.kind == Outgoing::Kind::kMesh && !frame.binary;
  }

  /// Keeps Impl's count of clients with a mesh frame queued or being written up to date
  /// (ServerStats::clients_ready_for_mesh). O(queue).
  void note_mesh_pending() {
    const auto is_mesh = [](const Outgoing& o) { return o.kind == Outgoing::Kind::kMesh; };
    set_mesh_pending(!closing_ && ((writing_ && is_mesh(in_flight_)) ||
                                   std::any_of(queue_.begin(), queue_.end(), is_mesh)));
  }

  void set_mesh_pending(bool pending) {
    if (pending == mesh_pending_) return;
    mesh_pending_ = pending;
    if (pending)
      ++server_.counters_.clients_waiting_for_mesh;
    else
      --server_.counters_.clients_waiting_for_mesh;
  }

  void on_accept(error_code ec) {
    if (ec) return;
    if (!server_.add_client(shared_from_this())) return;
    do_read();
  }

  void do_read() {
    ws_.async_read(in_, beast::bind_front_handler(&WsSession::on_read, shared_from_this()));
  }

  void on_read(error_code ec, std::size_t) {
    if (ec) {
      // An oversized message ends here too: Beast has sent close code 1009 already.
      if (ec == websocket::error::message_too_big) ++server_.counters_.clients_closed_bad;
      return finish();
    }
    const std::string text = beast::buffers_to_string(in_.data());
    in_.consume(in_.size());
    if (!ws_.got_text()) return refuse(websocket::close_code::unknown_data);
    const std::optional<ClientMessage> message = parse_client_message(text);
    if (!message) return refuse(websocket::close_code::policy_error);
    if (message->type == ClientMessage::Type::kMapAck) {
      // The next round sent and not yet acknowledged, or the connection goes. Bounded by the
      // rounds sent, so not held against the message rate.
      if (message->round != rounds_acked_ + 1 || rounds_acked_ == rounds_sent_)
        return refuse(websocket::close_code::policy_error);
      ++rounds_acked_;
      ++server_.counters_.map_acks;
      if (!writing_) write_next();
    } else if (!take_token()) {
      return refuse(websocket::close_code::policy_error);
    }
    do_read();
  }

  bool take_token() {
    const auto now = std::chrono::steady_clock::now();
    const double seconds = std::chrono::duration<double>(now - last_refill_).count();
    last_refill_ = now;
    tokens_ = std::min(server_.config_.client_message_burst,
                       tokens_ + seconds * server_.config_.client_messages_per_second);
    if (tokens_ < 1.0) return false;
    tokens_ -= 1.0;
    return true;
  }

  void refuse(websocket::close_code code) {
    ++server_.counters_.clients_closed_bad;
    if (closing_) return;
    closing_ = true;
    queue_.clear();
    // The close handshake is bounded by the stream's timeout; then the socket goes.
    ws_.async_close(code, [self = shared_from_this()](error_code) { self->finish(); });
  }

  void finish() {
    closing_ = true;
    queue_.clear();
    set_mesh_pending(false);
    pace_.cancel();
    server_.remove_client(shared_from_this());
    error_code ec;
    beast::get_lowest_layer(ws_).socket().close(ec);
  }

  void write_next() {
    // Stats and mesh frames first, then map blocks, the end message last. A new round of
    // blocks starts only while fewer than map_rounds_in_flight rounds wait for the viewer's
    // acknowledgement (ServerConfig).
    const bool frame_first = !queue_.empty() && queue_.front().kind != Outgoing::Kind::kEnd;
    const std::uint32_t window =
        static_cast<std::uint32_t>(std::max<std::size_t>(server_.config_.map_rounds_in_flight, 1));
    const bool blocks_now =
        !blocks_waiting_.empty() && (round_open_ || rounds_sent_ - rounds_acked_ < window);
    const bool end_now = !queue_.empty() && blocks_waiting_.empty() && blocks_later_.empty();
    if (closing_ || !(frame_first || blocks_now || end_now)) {
      writing_ = false;
      return;
    }
    writing_ = true;
    if (frame_first || !blocks_now) {
      in_flight_ = std::move(queue_.front());
      queue_.pop_front();
    } else {
      in_flight_ = block_batch();
    }
    // A bandwidth cap (ServerConfig::client_megabits_per_second) waits until the previous
    // frame's bytes have "left" at the capped rate; the frame taken stays in_flight_.
    if (server_.config_.client_megabits_per_second > 0.0 &&
        next_send_ > std::chrono::steady_clock::now()) {
      pace_.expires_at(next_send_);
      pace_.async_wait([self = shared_from_this()](error_code ec) {
        if (ec || self->closing_) {
          self->writing_ = false;
          return;
        }
        self->start_write();
      });
      return;
    }
    start_write();
  }

  void start_write() {
    write_started_ = std::chrono::steady_clock::now();
    ws_.binary(in_flight_.binary);
    ws_.async_write(asio::buffer(*in_flight_.data),
                    beast::bind_front_handler(&WsSession::on_write, shared_from_this()));
  }

  void on_write(error_code ec, std::size_t bytes) {
    if (ec) return finish();
    writing_ = false;
    note_mesh_pending();
    ++server_.counters_.frames_sent;
    server_.counters_.bytes_sent += bytes;
    if (in_flight_.kind == Outgoing::Kind::kEnd) ++server_.counters_.ends_sent;
    const double rate = server_.config_.client_megabits_per_second;
    if (rate > 0.0)
      next_send_ =
          write_started_ +
          std::chrono::duration_cast<std::chrono::steady_clock::duration>(
              std::chrono::duration<double>(8.0 * static_cast<double>(bytes) / (rate * 1e6)));
    write_next();
  }

  websocket::stream<beast::tcp_stream> ws_;
  beast::flat_buffer in_;
  Server::Impl& server_;
  std::deque<Outgoing> queue_;        // not yet started
  NearestBlockQueue blocks_waiting_;  // the round's blocks to send, nearest the sensor first
  NearestBlockQueue blocks_later_;    // marked while a round is sent and sent in it already
  bool round_open_ = false;           // a round's first batch is cut, its last not yet
  std::uint32_t rounds_sent_ = 0;     // map rounds closed ({"type":"map_round"} queued)
  std::uint32_t rounds_acked_ = 0;    // rounds the viewer has acknowledged
  // publish_blocks()' `shown` messages: each waiting block has the generation (a count of the
  // publications with one) at which it began to wait; a message goes once no block of its
  // generation or an earlier one waits.
  std::uint64_t generation_ = 0;
  std::map<BlockKey, std::uint64_t> block_generation_;
  std::map<std::uint64_t, std::size_t> waiting_by_generation_;
  std::deque<std::pair<std::uint64_t, std::shared_ptr<const std::string>>> shown_;
  Outgoing in_flight_;  // being written (its bytes must live until the write ends)
  asio::steady_timer pace_{ws_.get_executor()};
  std::chrono::steady_clock::time_point write_started_, next_send_;
  bool writing_ = false;
  bool closing_ = false;
  bool mesh_pending_ = false;  // counted in Impl::Counters::clients_waiting_for_mesh
  double tokens_;
  std::chrono::steady_clock::time_point last_refill_;
};

/// One HTTP connection: GET/HEAD of the fixed resources, or the upgrade to a WebSocket client.
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket socket, Server::Impl& server)
      : stream_(std::move(socket)), server_(server) {}

  void run() { do_read(); }

  void close() {
    error_code ec;
    stream_.socket().shutdown(tcp::socket::shutdown_both, ec);
    stream_.socket().close(ec);
  }

 private:
  void do_read() {
    parser_.emplace();
    parser_->header_limit(8 * 1024);
    parser_->body_limit(1024);
    stream_.expires_after(std::chrono::seconds(15));
    http::async_read(stream_, buffer_, *parser_,
                     beast::bind_front_handler(&HttpSession::on_read, shared_from_this()));
  }

  void on_read(error_code ec, std::size_t) {
    if (ec) return finish();
    http::request<http::string_body> request = parser_->release();
    if (websocket::is_upgrade(request)) return upgrade(std::move(request));
    respond(request);
  }

  void upgrade(http::request<http::string_body> request) {
    const std::string target(request.target());
    if (target != server_.config_.websocket_path)
      return send_error(request, http::status::not_found, "no such endpoint\n");
    if (server_.clients_.size() >= server_.config_.max_clients) {
      ++server_.counters_.clients_refused;
      return send_error(request, http::status::service_unavailable, "too many viewers\n");
    }
    stream_.expires_never();
    auto session = std::make_shared<WsSession>(stream_.release_socket(), server_);
    server_.connections_.erase(shared_from_this());
    session->run(std::move(request));
  }

  void respond(const http::request<http::string_body>& request) {
    ++server_.counters_.http_requests;
    if (request.method() != http::verb::get && request.method() != http::verb::head)
      return send_error(request, http::status::method_not_allowed, "read-only server\n");
    std::string path(request.target());
    path = path.substr(0, path.find('?'));
    const auto found = server_.config_.resources.find(path);
    if (found == server_.config_.resources.end())
      return send_error(request, http::status::not_found, "not found\n");
    auto response =
        std::make_shared<http::response<http::string_body>>(http::status::ok, request.version());
    response->set(http::field::server, "meshflow");
    response->set(http::field::content_type, found->second.content_type);
    response->set(http::field::cache_control, "no-store");
    response->set("X-Content-Type-Options", "nosniff");
    if (request.method() == http::verb::get) response->body() = *found->second.body;
    response->prepare_payload();
    if (request.method() == http::verb::head) response->content_length(found->second.body->size());
    response->keep_alive(request.keep_alive());
    write(std::move(response));
  }

  void send_error(const http::request<http::string_body>& request, http::status status,
                  const char* text) {
    auto response = std::make_shared<http::response<http::string_body>>(status, request.version());
    response->set(http::field::server, "meshflow");
    response->set(http::field::content_type, "text/plain; charset=utf-8");
    response->body() = text;
    response->prepare_payload();
    response->keep_alive(false);
    write(std::move(response));
  }

  void write(std::shared_ptr<http::response<http::string_body>> response) {
    response_ = std::move(response);
    stream_.expires_after(std::chrono::seconds(30));
    http::async_write(stream_, *response_,
                      beast::bind_front_handler(&HttpSession::on_write, shared_from_this()));
  }

  void on_write(error_code ec, std::size_t) {
    const bool keep = !ec && response_->keep_alive();
    response_.reset();
    if (!keep) return finish();
    do_read();
  }

  void finish() {
    close();
    server_.connections_.erase(shared_from_this());
  }

  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
  Server::Impl& server_;
  std::optional<http::request_parser<http::string_body>> parser_;
  std::shared_ptr<http::response<http::string_body>> response_;
};

void Server::Impl::do_accept() {
  acceptor_.async_accept([this](error_code ec, tcp::socket socket) {
    if (stopping_) return;
    if (!ec) {
      if (connections_.size() >= config_.max_connections) {
        error_code ignored;
        socket.close(ignored);
      } else {
        auto session = std::make_shared<HttpSession>(std::move(socket), *this);
        connections_.insert(session);
        session->run();
      }
    }
    do_accept();
  });
}

void Server::Impl::shut_down() {
  stopping_ = true;
  error_code ec;
  acceptor_.close(ec);
  for (const auto& client : std::set<std::shared_ptr<WsSession>>(clients_)) client->close();
  for (const auto& connection : std::set<std::shared_ptr<HttpSession>>(connections_))
    connection->close();
  clients_.clear();
  connections_.clear();
  counters_.clients = 0;
  counters_.clients_waiting_for_mesh = 0;
  ioc_.stop();
}

void Server::Impl::drain() {
  std::shared_ptr<const MeshMessage> mesh;
  std::shared_ptr<const std::string> stats;
  bool finish = false;
  std::map<BlockKey, std::shared_ptr<const std::string>> blocks;
  std::vector<std::shared_ptr<const std::string>> shown;
  {
    std::lock_guard<std::mutex> lock(pending_mutex_);
    blocks.swap(pending_blocks_);
    shown.swap(pending_shown_);
    if (pending_focus_) focus_ = *std::exchange(pending_focus_, std::nullopt);
    mesh = std::move(pending_mesh_);
    stats = std::move(pending_stats_);
    pending_mesh_.reset();
    pending_stats_.reset();
    finish = std::exchange(pending_finish_, false);
    drain_posted_ = false;
  }
  if (stopping_) return;
  // Stats first: a few hundred bytes that would otherwise wait behind a whole mesh.
  if (stats) {
    current_stats_ = stats;
    for (const auto& client : clients_) client->enqueue({Outgoing::Kind::kStats, false, stats});
  }
  if (mesh) {
    current_mesh_ = mesh;
    for (const auto& client : clients_)
      for (const Outgoing& frame : mesh->frames) client->enqueue(frame);
  }
  if (!blocks.empty() || !shown.empty()) {
    std::vector<BlockKey> keys;
    keys.reserve(blocks.size());
    for (auto& [key, payload] : blocks) {
      blocks_[key] = std::move(payload);
      keys.push_back(key);
    }
    for (const auto& client : clients_) client->mark_blocks(keys, focus_, shown);
  }
  if (finish && !finished_) {
    finished_ = true;
    for (const auto& client : clients_) client->enqueue(end_message());
  }
}

bool Server::Impl::add_client(const std::shared_ptr<WsSession>& session) {
  if (stopping_) {
    session->close();
    return false;
  }
  clients_.insert(session);
  counters_.clients = clients_.size();
  ++counters_.clients_accepted;
  if (current_stats_) session->enqueue({Outgoing::Kind::kStats, false, current_stats_});
  if (current_mesh_)
    for (const Outgoing& frame : current_mesh_->frames) session->enqueue(frame);
  if (!blocks_.empty()) {
    std::vector<BlockKey> keys;
    keys.reserve(blocks_.size());
    for (const auto& entry : blocks_) keys.push_back(entry.first);
    session->mark_blocks(keys, focus_);
  }
  if (finished_) session->enqueue(end_message());
  return true;
}

void Server::Impl::remove_client(const std::shared_ptr<WsSession>& session) {
  clients_.erase(session);
  counters_.clients = clients_.size();
}

Server::Server(ServerConfig config) : impl_(std::make_unique<Impl>(std::move(config))) {}

Server::~Server() = default;

const std::string& Server::host() const { return impl_->host_; }

std::uint16_t Server::port() const { return impl_->port_; }

std::string Server::url() const {
  const bool v6 = impl_->host_.find(':') != std::string::npos;
  return "http://" + (v6 ? "[" + impl_->host_ + "]" : impl_->host_) + ":" +
         std::to_string(impl_->port_) + "/";
}

namespace {

/// A binary mesh frame: u32 id, u32 offset (little-endian), then image[begin, end).
Outgoing mesh_chunk(std::uint32_t id, const std::vector<unsigned char>& image, std::size_t begin,
                    std::size_t end) {
  std::string frame(8 + (end - begin), '\0');
  const std::uint32_t fields[2] = {id, static_cast<std::uint32_t>(begin)};
  for (int f = 0; f < 2; ++f)
    for (int b = 0; b < 4; ++b)
      frame[static_cast<std::size_t>(4 * f + b)] = static_cast<char>(fields[f] >> (8 * b));
  std::memcpy(frame.data() + 8, image.data() + begin, end - begin);
  return {Outgoing::Kind::kMesh, true, std::make_shared<const std::string>(std::move(frame))};
}

/// Whether a progressive image is refined by its single-rate image of `single_bytes` rather
/// than by its packets (`packet_bytes`): ServerConfig::single_rate_within_s.
bool refine_with_single_rate(const ServerConfig& config, std::size_t single_bytes,
                             std::size_t packet_bytes) {
  if (single_bytes == 0 || single_bytes >= packet_bytes || config.single_rate_within_s <= 0.0)
    return false;
  const double rate = config.client_megabits_per_second;
  return rate <= 0.0 ||
         8.0 * static_cast<double>(single_bytes) / (rate * 1e6) <= config.single_rate_within_s;
}

}  // namespace

void Server::publish_mesh(std::vector<unsigned char> mfc, std::vector<unsigned char> single_rate) {
  const MeshStreamPlan plan = plan_mesh_stream(mfc, impl_->config_.chunk_bytes);
  MeshStreamPlan single_plan;
  if (!single_rate.empty()) {
    single_plan = plan_mesh_stream(single_rate, impl_->config_.chunk_bytes, "single-rate image");
    if (single_plan.progressive || single_plan.vertices != plan.vertices ||
        single_plan.triangles != plan.triangles)
      throw Error("single-rate image", "header",
                  "a single-rate image of the published mesh's " + std::to_string(plan.vertices) +
                      " vertices and " + std::to_string(plan.triangles) + " triangles");
  }
  const bool single =
      plan.progressive &&
      refine_with_single_rate(impl_->config_, single_rate.size(), mfc.size() - plan.base_end);
  const std::uint32_t id = static_cast<std::uint32_t>(++impl_->mesh_id_) & 0x7fffffffu;
  auto message = std::make_shared<MeshMessage>();
  nlohmann::json header = {{"type", "mesh"},
                           {"id", id},
                           {"kind", plan.progressive ? "progressive" : "edgebreaker"},
                           {"bytes", mfc.size()},
                           {"base_end", plan.base_end},
                           {"packet_ends", plan.packet_ends},
                           {"vertices", plan.vertices},
                           {"triangles", plan.triangles},
                           {"refine", single ? "single_rate" : "packets"}};
  if (single) {
    // The base, then the single-rate image in chunks of its own (cut anywhere: it decodes
    // only whole).
    header["single_rate_bytes"] = single_rate.size();
    header["chunks"] = 1 + (single_rate.size() + impl_->config_.chunk_bytes - 1) /
                               std::max<std::size_t>(impl_->config_.chunk_bytes, 1);
    message->frames.push_back(
        {Outgoing::Kind::kMesh, false, std::make_shared<const std::string>(header.dump())});
    message->frames.push_back(mesh_chunk(id, mfc, 0, plan.base_end));
    const std::size_t step = std::max<std::size_t>(impl_->config_.chunk_bytes, 1);
    for (std::size_t begin = 0; begin < single_rate.size(); begin += step)
      message->frames.push_back(mesh_chunk(id | 0x80000000u, single_rate, begin,
                                           std::min(single_rate.size(), begin + step)));
  } else {
    header["chunks"] = plan.chunk_ends.size();
    message->frames.push_back(
        {Outgoing::Kind::kMesh, false, std::make_shared<const std::string>(header.dump())});
    std::size_t begin = 0;
    for (std::size_t end : plan.chunk_ends) {
      message->frames.push_back(mesh_chunk(id, mfc, begin, end));
      begin = end;
    }
  }
  ++impl_->counters_.meshes;
  impl_->publish(std::move(message), nullptr);
}

void Server::publish_stats(std::string json) {
  impl_->publish(nullptr, std::make_shared<const std::string>(std::move(json)));
}

void Server::finish() { impl_->publish(nullptr, nullptr, true); }

void Server::publish_blocks(std::vector<MapBlock> blocks, std::optional<BlockPoint> focus,
                            std::string shown) {
  impl_->counters_.blocks_published += blocks.size();
  impl_->publish(nullptr, nullptr, false, std::move(blocks), focus, std::move(shown));
}

ServerStats Server::stats() const {
  const Impl::Counters& c = impl_->counters_;
  ServerStats s;
  s.clients = c.clients;
  s.clients_accepted = c.clients_accepted;
  s.clients_refused = c.clients_refused;
  s.clients_closed_bad_message = c.clients_closed_bad;
  s.frames_sent = c.frames_sent;
  s.frames_dropped = c.frames_dropped;
  s.bytes_sent = c.bytes_sent;
  s.http_requests = c.http_requests;
  s.meshes_published = c.meshes;
  s.publications_replaced = c.publications_replaced;
  s.max_client_queue_frames = c.max_client_queue;
  s.blocks_published = c.blocks_published;
  s.blocks_sent = c.blocks_sent;
  s.blocks_superseded = c.blocks_superseded;
  s.max_client_pending_blocks = c.max_pending_blocks;
  s.ends_sent = c.ends_sent;
  s.map_rounds_sent = c.map_rounds;
  s.map_rounds_acknowledged = c.map_acks;
  s.shown_superseded = c.shown_superseded;
  const std::size_t waiting = c.clients_waiting_for_mesh;
  s.clients_ready_for_mesh = s.clients > waiting ? s.clients - waiting : 0;
  return s;
}

}  // namespace meshflow::serve
