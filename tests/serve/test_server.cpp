// The serving layer: what it binds to by default, that it serves only its fixed resources, that a
// published mesh streams in chunks (base first) whose prefixes decode to growing levels ending
// in the full mesh, and that bad, oversized, flooding, surplus or stalled clients cost the
// producer nothing. Every client here talks to 127.0.0.1 with bounded waits.

#include <gtest/gtest.h>

#include <algorithm>
#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "nodes/compress/compressed_mesh.h"
#include "nodes/compress/progressive_mesh.h"
#include "runtime/error.h"
#include "serve/client_message.h"
#include "serve/mesh_stream.h"
#include "serve/server.h"
#include "tests/serve/test_client.h"
#include "web/mfc_decoder.h"

namespace meshflow::serve {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using error_code = boost::system::error_code;
using namespace std::chrono_literals;
using testing::Client;
using testing::config_with_page;
using testing::wavy_grid;

/// One HTTP request to the server; the response (status 0 if none came).
http::response<http::string_body> http_request(std::uint16_t port, http::verb verb,
                                               const std::string& target) {
  asio::io_context ioc;
  beast::tcp_stream stream(ioc);
  stream.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), port));
  http::request<http::string_body> request(verb, target, 11);
  request.set(http::field::host, "127.0.0.1");
  request.keep_alive(false);
  http::write(stream, request);
  beast::flat_buffer buffer;
  http::response<http::string_body> response;
  error_code ec;
  http::read(stream, buffer, response, ec);
  return response;
}

TEST(ClientMessage, OnlyHelloPingAndMapAcknowledgementObjects) {
  EXPECT_TRUE(valid_client_message(R"({"type":"hello"})"));
  EXPECT_TRUE(valid_client_message(R"({"type":"ping","t":1})"));
  const auto ack = parse_client_message(R"({"type":"map_ack","round":4294967295})");
  ASSERT_TRUE(ack);
  EXPECT_EQ(ack->type, ClientMessage::Type::kMapAck);
  EXPECT_EQ(ack->round, 4294967295u);
  EXPECT_EQ(parse_client_message(R"({"round":7,"type":"map_ack"})")->round, 7u);
  for (const char* bad :
       {"", "hello", "[]", "{}", R"({"type":1})", R"({"type":"get"})", R"({"type":"hello")",
        "\xff\xfe", R"("type")", R"({"type":"map_ack"})", R"({"type":"map_ack","round":0})",
        R"({"type":"map_ack","round":-1})", R"({"type":"map_ack","round":1.0})",
        R"({"type":"map_ack","round":1e3})", R"({"type":"map_ack","round":"1"})",
        R"({"type":"map_ack","round":null})", R"({"type":"map_ack","round":4294967296})",
        R"({"type":"MAP_ACK","round":1})"})
    EXPECT_FALSE(valid_client_message(bad)) << bad;
}

TEST(Server, BindsLoopbackByDefault) {
  EXPECT_EQ(ServerConfig{}.host, "127.0.0.1");
  Server server{ServerConfig{}};
  EXPECT_EQ(server.host(), "127.0.0.1");
  EXPECT_NE(server.port(), 0);
  EXPECT_EQ(server.url(), "http://127.0.0.1:" + std::to_string(server.port()) + "/");
}

TEST(Server, RefusesAHostThatIsNotAnAddress) {
  ServerConfig config;
  config.host = "example.invalid";
  EXPECT_THROW(Server{config}, Error);
}

TEST(Server, ServesOnlyItsFixedResources) {
  Server server{config_with_page()};
  auto response = http_request(server.port(), http::verb::get, "/");
  EXPECT_EQ(response.result(), http::status::ok);
  EXPECT_EQ(response.body(), "<p>page</p>");
  EXPECT_EQ(response[http::field::content_type], "text/html");
  for (const char* target : {"/etc/passwd", "/../../../../etc/passwd", "/%2e%2e/etc/passwd",
                             "//etc/passwd", "/index.html"})
    EXPECT_EQ(http_request(server.port(), http::verb::get, target).result(),
              http::status::not_found)
        << target;
  EXPECT_EQ(http_request(server.port(), http::verb::post, "/").result(),
            http::status::method_not_allowed);
  EXPECT_EQ(http_request(server.port(), http::verb::put, "/").result(),
            http::status::method_not_allowed);
}

TEST(Server, StreamsAProgressiveMeshBaseFirstAndEveryPrefixDecodes) {
  const TriangleMesh mesh = wavy_grid(48);
  compress::CompressConfig cc;
  cc.splits_per_packet = 64;
  cc.base_ratio = 0.05f;
  const std::vector<unsigned char> mfc = compress::compress_progressive(mesh, cc);
  ServerConfig config = config_with_page();
  config.chunk_bytes = 512;
  Server server{config};
  Client client;
  ASSERT_FALSE(client.connect(server.port()));
  ASSERT_FALSE(client.write(R"({"type":"hello"})"));
  server.publish_stats(R"({"type":"stats","stages":{"compress_ms":1.5}})");
  server.publish_mesh(mfc);

  std::string message;
  bool binary = false;
  nlohmann::json header;
  std::vector<unsigned char> received;
  std::uint32_t last_triangles = 0;
  int levels = 0;
  bool got_stats = false;
  while (header.is_null() || received.size() < header["bytes"].get<std::size_t>()) {
    ASSERT_FALSE(client.read(message, binary));
    if (!binary) {
      const nlohmann::json doc = nlohmann::json::parse(message);
      if (doc["type"] == "stats") got_stats = true;
      if (doc["type"] == "mesh") header = doc;
      continue;
    }
    ASSERT_FALSE(header.is_null()) << "a chunk came before its mesh's header";
    ASSERT_GE(message.size(), 8u);
    std::uint32_t id = 0, offset = 0;
    std::memcpy(&id, message.data(), 4);
    std::memcpy(&offset, message.data() + 4, 4);
    EXPECT_EQ(id, header["id"].get<std::uint32_t>());
    ASSERT_EQ(offset, received.size()) << "chunks arrive in order";
    received.insert(received.end(), message.begin() + 8, message.end());
    const std::size_t base_end = header["base_end"];
    if (received.size() == header["bytes"].get<std::size_t>()) break;
    // Every chunk ends at the base or a packet's end: the prefix decodes as a level of detail.
    const std::vector<std::size_t> ends = header["packet_ends"];
    int packets = 0;
    while (packets < static_cast<int>(ends.size()) &&
           ends[static_cast<std::size_t>(packets)] <= received.size())
      ++packets;
    const std::size_t prefix =
        packets == 0 ? base_end : ends[static_cast<std::size_t>(packets - 1)];
    ASSERT_EQ(prefix, received.size());
    ASSERT_EQ(mf_decode(received.data(), received.size(), base_end, packets), 0) << mf_error();
    EXPECT_GT(mf_triangle_count(), last_triangles) << "levels grow";
    last_triangles = mf_triangle_count();
    ++levels;
  }
  EXPECT_TRUE(got_stats);
  EXPECT_EQ(header["kind"], "progressive");
  EXPECT_GE(levels, 3) << "base and at least two finer levels before the full mesh";
  ASSERT_EQ(received, mfc);
  ASSERT_EQ(mf_decode(received.data(), received.size(), 0, -1), 0) << mf_error();
  EXPECT_EQ(mf_triangle_count(), mesh.triangles.size());
  EXPECT_EQ(mf_vertex_count(), mesh.vertices.size());
  EXPECT_EQ(header["triangles"].get<std::size_t>(), mesh.triangles.size());
  EXPECT_EQ(header["vertices"].get<std::size_t>(), mesh.vertices.size());
  const TriangleMesh full = compress::decompress_mesh(mfc, "test");
  EXPECT_EQ(0, std::memcmp(mf_positions(), full.vertices[0].data(),
                           full.vertices.size() * sizeof(full.vertices[0])));
  EXPECT_EQ(0, std::memcmp(mf_indices(), full.triangles[0].data(),
                           full.triangles.size() * sizeof(full.triangles[0])));
  EXPECT_NE(mf_decode(received.data(), received.size() - 1, 0, -1), 0) << "checksum checked";
}

/// What a client read of one mesh: its header, the progressive bytes and the single-rate bytes
/// (chunks whose id has the high bit), each checked to arrive in order.
struct ReadMesh {
  nlohmann::json header;
  std::vector<unsigned char> progressive, single_rate;
};
ReadMesh read_one_mesh(Client& client) {
  ReadMesh r;
  const auto done = [&r] {
    if (r.header.is_null()) return false;
    if (r.header["refine"] == "single_rate")
      return r.single_rate.size() == r.header["single_rate_bytes"].get<std::size_t>();
    return r.progressive.size() == r.header["bytes"].get<std::size_t>();
  };
  while (!done()) {
    std::string message;
    bool binary = false;
    if (client.read(message, binary)) {
      ADD_FAILURE() << "the stream ended before the mesh";
      return r;
    }
    if (!binary) {
      const nlohmann::json doc = nlohmann::json::parse(message);
      if (doc["type"] == "mesh") r.header = doc;
      continue;
    }
    std::uint32_t id = 0, offset = 0;
    std::memcpy(&id, message.data(), 4);
    std::memcpy(&offset, message.data() + 4, 4);
    const bool single = (id & 0x80000000u) != 0;
    EXPECT_EQ(id & 0x7fffffffu, r.header["id"].get<std::uint32_t>());
    std::vector<unsigned char>& to = single ? r.single_rate : r.progressive;
    EXPECT_EQ(offset, to.size()) << "chunks arrive in order";
    to.insert(to.end(), message.begin() + 8, message.end());
  }
  return r;
}

// A mesh's progressive image (64 splits per packet) and its single-rate image.
std::pair<std::vector<unsigned char>, std::vector<unsigned char>> progressive_and_single_rate(
    const TriangleMesh& mesh) {
  compress::CompressConfig cc;
  cc.splits_per_packet = 64;
  return {compress::compress_progressive(mesh, cc), compress::compress_mesh(mesh, cc)};
}

TEST(Server, AFastLinkGetsTheBaseThenTheSingleRateImage) {
  // The single-rate image is far smaller than the split packets: after the base (a level of
  // its own), it is sent instead of them, and decodes to the whole mesh.
  const TriangleMesh mesh = wavy_grid(60, 0.02f);
  const auto [progressive, single] = progressive_and_single_rate(mesh);
  const std::size_t base_end = plan_mesh_stream(progressive, 1).base_end;
  ASSERT_LT(single.size(), progressive.size() - base_end);
  ServerConfig config = config_with_page();
  config.chunk_bytes = 2048;
  Server server{config};
  Client client;
  ASSERT_FALSE(client.connect(server.port()));
  server.publish_mesh(progressive, single);
  const ReadMesh r = read_one_mesh(client);
  EXPECT_EQ(r.header["refine"], "single_rate");
  EXPECT_EQ(r.header["kind"], "progressive");
  ASSERT_EQ(r.progressive.size(), base_end) << "only the base of the progressive image";
  EXPECT_TRUE(std::equal(r.progressive.begin(), r.progressive.end(), progressive.begin()));
  ASSERT_EQ(mf_decode(r.progressive.data(), r.progressive.size(), base_end, 0), 0) << mf_error();
  EXPECT_LT(mf_triangle_count(), mesh.triangles.size() / 2) << "the base is coarse";
  EXPECT_EQ(r.single_rate, single);
  ASSERT_EQ(mf_decode(r.single_rate.data(), r.single_rate.size(), 0, -1), 0) << mf_error();
  EXPECT_EQ(mf_triangle_count(), mesh.triangles.size());
  EXPECT_EQ(mf_vertex_count(), mesh.vertices.size());
}

TEST(Server, ANarrowLinkGetsTheSplitPackets) {
  // At 0.02 Mbit/s the single-rate image would take over a second: the packets refine the base
  // level by level instead (ServerConfig::single_rate_within_s).
  const TriangleMesh mesh = wavy_grid(60, 0.02f);
  const auto [progressive, single] = progressive_and_single_rate(mesh);
  ASSERT_GT(8.0 * static_cast<double>(single.size()) / 0.02e6, 1.0);
  ServerConfig config = config_with_page();
  config.client_megabits_per_second = 0.02;
  config.chunk_bytes = 1 << 20;  // few frames: the cap's wait is per frame
  config.single_rate_within_s = 1.0;
  Server server{config};
  Client client;
  ASSERT_FALSE(client.connect(server.port()));
  server.publish_mesh(progressive, single);
  const ReadMesh r = read_one_mesh(client);
  EXPECT_EQ(r.header["refine"], "packets");
  EXPECT_EQ(r.progressive, progressive);
  EXPECT_TRUE(r.single_rate.empty());
}

TEST(Server, RefusesASingleRateImageOfAnotherMesh) {
  Server server{config_with_page()};
  const std::vector<unsigned char> progressive = compress::compress_progressive(wavy_grid(20));
  EXPECT_THROW(server.publish_mesh(progressive, compress::compress_mesh(wavy_grid(21))), Error);
  EXPECT_THROW(server.publish_mesh(progressive, progressive), Error);
}

TEST(Server, AClientThatStopsReadingIsNotReadyForAMesh) {
  // ServerStats::clients_ready_for_mesh, what a run's encoder waits for: a client that reads is
  // ready again once a mesh is written; one that never reads keeps its mesh's frames queued.
  const std::vector<unsigned char> mfc = compress::compress_mesh(wavy_grid(240, 0.05f));
  ASSERT_GT(mfc.size(), 50'000u);
  ServerConfig config = config_with_page();
  config.chunk_bytes = 4096;
  Server server{config};
  Client stalled(4096);
  ASSERT_FALSE(stalled.connect(server.port()));
  for (int i = 0; i < 1000 && server.stats().clients < 1; ++i) std::this_thread::sleep_for(10ms);
  EXPECT_EQ(server.stats().clients_ready_for_mesh, 1u) << "nothing queued yet";
  // 5 MB of meshes: more than the kernel's buffers take with a 4 kB receive buffer; from then
  // on the client keeps its newest mesh's frames queued.
  for (int i = 0; i < 100; ++i) {
    server.publish_mesh(mfc);
    std::this_thread::sleep_for(2ms);
  }
  std::this_thread::sleep_for(200ms);
  EXPECT_EQ(server.stats().clients_ready_for_mesh, 0u);

  Client reader;
  ASSERT_FALSE(reader.connect(server.port()));
  for (int i = 0; i < 1000 && server.stats().clients < 2; ++i) std::this_thread::sleep_for(10ms);
  const ReadMesh r = read_one_mesh(reader);
  EXPECT_EQ(r.progressive, mfc);
  for (int i = 0; i < 500 && server.stats().clients_ready_for_mesh < 1; ++i)
    std::this_thread::sleep_for(10ms);
  const ServerStats s = server.stats();
  EXPECT_EQ(s.clients, 2u);
  EXPECT_EQ(s.clients_ready_for_mesh, 1u) << "the reader is ready, the stalled client is not";
}

TEST(Server, CapsEachClientsBandwidth) {
  // 0.8 Mbit/s = 100 kB/s: a 50+ kB mesh in 4 kB frames takes about half a second or more.
  const std::vector<unsigned char> mfc =
      compress::compress_progressive(wavy_grid(150, 0.05f), compress::CompressConfig{});
  ASSERT_GT(mfc.size(), 50'000u);
  ServerConfig config = config_with_page();
  config.client_megabits_per_second = 0.8;
  config.chunk_bytes = 4096;
  Server server{config};
  Client client;
  ASSERT_FALSE(client.connect(server.port()));
  const auto start = std::chrono::steady_clock::now();
  server.publish_mesh(mfc);
  std::size_t received = 0;
  while (received < mfc.size()) {
    std::string message;
    bool binary = false;
    ASSERT_FALSE(client.read(message, binary));
    if (binary) received += message.size() - 8;
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GT(seconds, 0.8 * static_cast<double>(mfc.size()) / 100e3) << mfc.size() << " bytes";
}

TEST(Server, ANewClientGetsTheCurrentMesh) {
  Server server{config_with_page()};
  server.publish_mesh(compress::compress_mesh(wavy_grid(8)));
  std::this_thread::sleep_for(50ms);
  Client client;
  ASSERT_FALSE(client.connect(server.port()));
  std::string message;
  bool binary = true;
  ASSERT_FALSE(client.read(message, binary));
  EXPECT_FALSE(binary);
  const nlohmann::json header = nlohmann::json::parse(message);
  EXPECT_EQ(header["type"], "mesh");
  EXPECT_EQ(header["kind"], "edgebreaker");
  EXPECT_EQ(header["triangles"], 2 * 7 * 7);
}

TEST(Server, RefusesAnInvalidMfcImage) {
  Server server{config_with_page()};
  EXPECT_THROW(server.publish_mesh({1, 2, 3}), Error);
}

TEST(Server, AnOversizedClientMessageClosesTheConnection) {
  ServerConfig config = config_with_page();
  config.max_client_message_bytes = 256;
  Server server{config};
  Client client;
  ASSERT_FALSE(client.connect(server.port()));
  ASSERT_FALSE(client.write(R"({"type":"hello","pad":")" + std::string(1000, 'x') + "\"}"));
  const error_code ec = client.read_until_closed();
  EXPECT_NE(ec, asio::error::timed_out);
  EXPECT_EQ(client.reason().code, websocket::close_code::too_big);
  // The server counts it when its read ends, after the close handshake the client saw.
  for (int i = 0; i < 1000 && server.stats().clients_closed_bad_message == 0; ++i)
    std::this_thread::sleep_for(10ms);
  EXPECT_EQ(server.stats().clients_closed_bad_message, 1u);
}

TEST(Server, MalformedClientMessagesCloseTheConnection) {
  Server server{config_with_page()};
  const std::vector<std::pair<std::string, bool>> bad = {
      {"not json", false},
      {"[1,2,3]", false},
      {R"({"type":"delete","path":"/etc/passwd"})", false},
      {R"({"kind":"hello"})", false},
      {std::string("\x01\x02\x03", 3), true}};
  for (const auto& [message, binary] : bad) {
    Client client;
    ASSERT_FALSE(client.connect(server.port()));
    ASSERT_FALSE(client.write(R"({"type":"ping"})"));  // a valid one first: kept open
    ASSERT_FALSE(client.write(message, binary));
    const error_code ec = client.read_until_closed();
    EXPECT_NE(ec, asio::error::timed_out) << message;
    EXPECT_EQ(client.reason().code,
              binary ? websocket::close_code::unknown_data : websocket::close_code::policy_error)
        << message;
  }
  EXPECT_EQ(server.stats().clients_closed_bad_message, bad.size());
}

TEST(Server, AFloodOfClientMessagesClosesTheConnection) {
  ServerConfig config = config_with_page();
  config.client_message_burst = 5;
  config.client_messages_per_second = 1;
  Server server{config};
  Client client;
  ASSERT_FALSE(client.connect(server.port()));
  for (int i = 0; i < 50; ++i)
    if (client.write(R"({"type":"ping"})")) break;
  EXPECT_NE(client.read_until_closed(), asio::error::timed_out);
  EXPECT_EQ(client.reason().code, websocket::close_code::policy_error);
}

TEST(Server, RefusesClientsBeyondTheLimit) {
  ServerConfig config = config_with_page();
  config.max_clients = 1;
  Server server{config};
  Client first, second;
  ASSERT_FALSE(first.connect(server.port()));
  for (int i = 0; i < 1000 && server.stats().clients < 1; ++i) std::this_thread::sleep_for(10ms);
  EXPECT_TRUE(second.connect(server.port()));
  EXPECT_EQ(server.stats().clients_refused, 1u);
  Client wrong_path;
  EXPECT_TRUE(wrong_path.connect(server.port(), "/../ws"));
}

TEST(Server, AClientThatNeverReadsDoesNotBlockPublishing) {
  // A mesh of over 50 kB, published 400 times (20 MB) to a client with a 4 kB receive buffer
  // that never reads: each publish returns at once, stale frames are dropped, and a reading
  // client still gets the newest mesh.
  const std::vector<unsigned char> mfc = compress::compress_mesh(wavy_grid(240, 0.05f));
  ASSERT_GT(mfc.size(), 50'000u);
  Server server{config_with_page()};
  Client stalled(4096);
  ASSERT_FALSE(stalled.connect(server.port()));
  for (int i = 0; i < 1000 && server.stats().clients < 1; ++i) std::this_thread::sleep_for(10ms);
  double slowest = 0.0;
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < 400; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    server.publish_mesh(mfc);
    server.publish_stats(R"({"type":"stats","frame":)" + std::to_string(i) + "}");
    slowest = std::max(
        slowest, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  const double total =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // Generous bounds (a loaded CI machine): a publish that waited on the stalled client would
  // wait forever.
  EXPECT_LT(slowest, 2.0) << "one publish waited on the network";
  EXPECT_LT(total, 30.0);
  // What the stalled client could not take was dropped (from its queue, or replaced before the
  // I/O thread took it), and its queue never held more than one mesh (header + one chunk of
  // this single-rate image), one stats message and the frame being written.
  const auto dropped = [&] {
    const ServerStats s = server.stats();
    return s.frames_dropped + s.publications_replaced;
  };
  for (int i = 0; i < 1000 && dropped() == 0; ++i) std::this_thread::sleep_for(10ms);
  EXPECT_GT(dropped(), 0u);
  EXPECT_LE(server.stats().max_client_queue_frames, 4u);

  Client reader;
  ASSERT_FALSE(reader.connect(server.port()));
  std::string message;
  bool binary = false;
  ASSERT_FALSE(reader.read(message, binary));
  EXPECT_EQ(nlohmann::json::parse(message)["frame"], 399) << "the newest stats first";
  ASSERT_FALSE(reader.read(message, binary));
  const nlohmann::json header = nlohmann::json::parse(message);
  EXPECT_EQ(header["type"], "mesh");
  EXPECT_EQ(header["id"], server.stats().meshes_published);
}

TEST(Server, FinishSendsTheEndAfterEverythingQueued) {
  const std::vector<unsigned char> mfc = compress::compress_mesh(wavy_grid(40));
  ServerConfig config = config_with_page();
  config.chunk_bytes = 256;
  Server server{config};
  Client early;
  ASSERT_FALSE(early.connect(server.port()));
  for (int i = 0; i < 1000 && server.stats().clients < 1; ++i) std::this_thread::sleep_for(10ms);
  server.publish_mesh(mfc);
  server.finish();
  Client late;  // connects after finish(): gets the mesh, then the end
  ASSERT_FALSE(late.connect(server.port()));
  for (Client* client : {&early, &late}) {
    std::size_t received = 0;
    std::string message;
    bool binary = false;
    for (;;) {
      ASSERT_FALSE(client->read(message, binary));
      if (binary) {
        received += message.size() - 8;
        continue;
      }
      if (nlohmann::json::parse(message)["type"] == "end") break;
    }
    EXPECT_EQ(received, mfc.size()) << "the end came after the whole mesh";
  }
}

}  // namespace
}  // namespace meshflow::serve
