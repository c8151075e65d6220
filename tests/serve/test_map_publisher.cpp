// A fused map sent block by block (serve/map_publisher.h): a viewer connected while meshflow's
// synthetic depth sequence is fused (reading only after the run, so blocks change again before
// it takes them) assembles, from the blocks it was sent, the mesh TsdfMesher::extract() gives:
// the same vertex and triangle counts (shared vertices welded by their grid edge) and every
// vertex within the quantisation of one of the fused mesh's. A viewer that never reads waits
// for at most one copy of each block. The live map's latency: a publication's `shown` message
// comes after every block of it, and a paced run lists each frame once, with times that agree.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <thread>
#include <unordered_map>
#include <utility>
#include <vector>

#include "graph/fusion_pipeline.h"
#include "graph/sequence_runner.h"
#include "nodes/compress/compressed_mesh.h"
#include "nodes/synthetic/depth_sequence.h"
#include "nodes/synthetic/scan_simulator.h"
#include "serve/map_publisher.h"
#include "serve/server.h"
#include "tests/serve/test_client.h"

namespace meshflow::serve {
namespace {

using namespace std::chrono_literals;
using testing::Client;
namespace asio = testing::asio;
namespace websocket = testing::websocket;
using testing::config_with_page;

constexpr float kVoxel = 0.05f;

std::uint32_t u32_at(const std::string& s, std::size_t at) {
  std::uint32_t v = 0;
  std::memcpy(&v, s.data() + at, 4);
  return v;
}

std::uint16_t u16_at(const std::string& s, std::size_t at) {
  std::uint16_t v = 0;
  std::memcpy(&v, s.data() + at, 2);
  return v;
}

/// What a viewer holds: the newest payload of every block it was sent, after the end message.
std::map<std::array<std::int32_t, 3>, std::string> read_blocks_to_end(Client& client) {
  std::map<std::array<std::int32_t, 3>, std::string> table;
  std::string message;
  bool binary = false;
  for (;;) {
    if (client.read(message, binary)) {
      ADD_FAILURE() << "the stream ended without the end message";
      return table;
    }
    if (!binary) {
      if (nlohmann::json::parse(message)["type"] == "end") return table;
      continue;
    }
    if (u32_at(message, 0) != 0) continue;  // a mesh chunk
    const std::uint32_t count = u32_at(message, 4);
    std::size_t at = 8;
    for (std::uint32_t i = 0; i < count; ++i) {
      std::array<std::int32_t, 3> key{};
      std::memcpy(key.data(), message.data() + at, 12);
      const std::uint32_t n = u32_at(message, at + 12);
      at += 16;
      table[key] = message.substr(at, n);
      at += n;
    }
    EXPECT_EQ(at, message.size());
  }
}

/// The viewer's map: every block decoded, vertices on shared edges welded by global edge.
TriangleMesh assemble(const std::map<std::array<std::int32_t, 3>, std::string>& table) {
  TriangleMesh mesh;
  std::map<std::array<std::int32_t, 4>, std::uint32_t> welded;  // global edge -> vertex
  for (const auto& [key, payload] : table) {
    if (payload.empty()) continue;
    const std::uint16_t shared = u16_at(payload, 0);
    const std::size_t mfc_at = 2 + 4 * static_cast<std::size_t>(shared);
    const TriangleMesh piece = compress::decompress_mesh(
        std::vector<unsigned char>(payload.begin() + static_cast<std::ptrdiff_t>(mfc_at),
                                   payload.end()),
        "block");
    std::vector<std::uint32_t> id(piece.vertices.size(), UINT32_MAX);
    for (std::uint16_t k = 0; k < shared; ++k) {
      const std::uint16_t vertex = u16_at(payload, 2 + 4 * k);
      std::uint32_t code = u16_at(payload, 2 + 4 * k + 2);
      const std::int32_t axis = static_cast<std::int32_t>(code % 3);
      code /= 3;
      const std::array<std::int32_t, 4> edge{key[0] * 8 + static_cast<std::int32_t>(code / 81),
                                             key[1] * 8 + static_cast<std::int32_t>(code / 9 % 9),
                                             key[2] * 8 + static_cast<std::int32_t>(code % 9),
                                             axis};
      const auto [it, fresh] =
          welded.emplace(edge, static_cast<std::uint32_t>(mesh.vertices.size()));
      if (fresh) mesh.vertices.push_back(piece.vertices[vertex]);
      id[vertex] = it->second;
    }
    for (std::size_t v = 0; v < piece.vertices.size(); ++v) {
      if (id[v] != UINT32_MAX) continue;
      id[v] = static_cast<std::uint32_t>(mesh.vertices.size());
      mesh.vertices.push_back(piece.vertices[v]);
    }
    for (const Triangle& t : piece.triangles)
      mesh.triangles.push_back({id[t[0]], id[t[1]], id[t[2]]});
  }
  return mesh;
}

/// Whether every vertex of `a` has one of `b` within `tolerance` on each axis (a grid of
/// tolerance-sized cells over b).
bool every_vertex_near(const TriangleMesh& a, const TriangleMesh& b, float tolerance) {
  const auto cell = [tolerance](const Eigen::Vector3f& p) {
    return std::array<std::int64_t, 3>{static_cast<std::int64_t>(std::floor(p.x() / tolerance)),
                                       static_cast<std::int64_t>(std::floor(p.y() / tolerance)),
                                       static_cast<std::int64_t>(std::floor(p.z() / tolerance))};
  };
  std::map<std::array<std::int64_t, 3>, std::vector<std::uint32_t>> grid;
  for (std::uint32_t i = 0; i < b.vertices.size(); ++i) grid[cell(b.vertices[i])].push_back(i);
  for (const Eigen::Vector3f& p : a.vertices) {
    const auto c = cell(p);
    bool found = false;
    for (int d = 0; d < 27 && !found; ++d) {
      const auto it = grid.find({c[0] + d % 3 - 1, c[1] + d / 3 % 3 - 1, c[2] + d / 9 - 1});
      if (it == grid.end()) continue;
      for (std::uint32_t i : it->second)
        if ((b.vertices[i] - p).cwiseAbs().maxCoeff() <= tolerance) found = true;
    }
    if (!found) return false;
  }
  return true;
}

std::unique_ptr<io::Sequence> small_depth_sequence() {
  synthetic::DepthSequenceConfig c;
  c.frames = 6;
  c.intrinsics = synthetic::scaled_default_camera(160, 120);
  return synthetic::make_depth_sequence(synthetic::demo_room_scene(), c);
}

FusionConfig fusion_config() {
  FusionConfig config;
  config.tsdf.voxel_size = kVoxel;
  config.frames.optimize.steps.clear();  // fused mesh = the mesher's
  return config;
}

TEST(MapPublisher, TheBlocksAViewerWasSentAssembleToTheFusedMesh) {
  Server server{config_with_page()};
  Client viewer;
  ASSERT_FALSE(viewer.connect(server.port()));
  for (int i = 0; i < 1000 && server.stats().clients < 1; ++i) std::this_thread::sleep_for(10ms);
  const FusionConfig config = fusion_config();
  FusionPipeline pipeline(config, 2);
  MapPublisher publisher(server, kVoxel, config.min_weight, /*min_interval_s=*/0.0);
  pipeline.set_integration_observer([&](const TsdfMap& map, const Eigen::Vector3f& sensor,
                                        const Frame&) { publisher.integrated(map, sensor); });
  const auto sequence = small_depth_sequence();
  run_sequence(pipeline, *sequence, {}, [](const Frame& f) { ASSERT_TRUE(f.ok()) << f.error; });
  publisher.finish(pipeline.map());
  server.finish();
  const TriangleMesh fused = pipeline.extract_mesh();
  ASSERT_GT(fused.triangles.size(), 1000u);

  const auto table = read_blocks_to_end(viewer);
  const TriangleMesh assembled = assemble(table);
  EXPECT_EQ(assembled.vertices.size(), fused.vertices.size());
  EXPECT_EQ(assembled.triangles.size(), fused.triangles.size());
  // Within the quantisation (voxel / 64, half a step per axis), both ways.
  const float tolerance = 0.5f * kVoxel / 64.0f + 1e-6f;
  EXPECT_TRUE(every_vertex_near(assembled, fused, tolerance));
  EXPECT_TRUE(every_vertex_near(fused, assembled, tolerance));
  const MapPublisherCounts c = publisher.counts();
  // The first integration always updates (a viewer, the coder idle); later ones may find the
  // coder busy. With finish()'s: at least two.
  EXPECT_GE(c.updates, 2u) << "blocks went out while the map grew";
  EXPECT_EQ(c.encode_errors, 0u);
  EXPECT_GT(server.stats().blocks_published, table.size()) << "blocks went again when they changed";
}

TEST(MapPublisher, AViewerThatNeverReadsWaitsForEachBlockAtMostOnce) {
  Server server{config_with_page()};
  Client stalled(4096);
  ASSERT_FALSE(stalled.connect(server.port()));
  for (int i = 0; i < 1000 && server.stats().clients < 1; ++i) std::this_thread::sleep_for(10ms);
  const FusionConfig config = fusion_config();
  FusionPipeline pipeline(config, 2);
  MapPublisher publisher(server, kVoxel, config.min_weight, 0.0);
  pipeline.set_integration_observer([&](const TsdfMap& map, const Eigen::Vector3f& sensor,
                                        const Frame&) { publisher.integrated(map, sensor); });
  run_sequence(pipeline, *small_depth_sequence(), {}, [](const Frame&) {});
  publisher.finish(pipeline.map());
  std::this_thread::sleep_for(100ms);
  const ServerStats s = server.stats();
  EXPECT_GT(s.blocks_published, pipeline.map().block_count() / 4);
  EXPECT_LE(s.max_client_pending_blocks, pipeline.map().block_count());
  EXPECT_LE(s.blocks_sent, s.blocks_published);
  EXPECT_LE(s.max_client_queue_frames, 3u);
}

std::shared_ptr<const std::string> filled(std::size_t n, char c) {
  return std::make_shared<const std::string>(n, c);
}

TEST(Server, AShownMessageComesAfterEveryBlockOfItsPublication) {
  ServerConfig config = config_with_page();
  config.chunk_bytes = 256;  // a block or two per batch
  Server server{config};
  Client viewer;
  ASSERT_FALSE(viewer.connect(server.port()));
  for (int i = 0; i < 1000 && server.stats().clients < 1; ++i) std::this_thread::sleep_for(10ms);
  std::vector<MapBlock> first;
  for (std::int32_t x = 0; x < 10; ++x) first.push_back({x, 0, 0, filled(200, 'a')});
  server.publish_blocks(std::move(first), BlockPoint{0, 0, 0}, R"({"type":"map_shown","n":1})");
  // Block 5 again (a newer payload), one more, then a publication without blocks.
  server.publish_blocks({{5, 0, 0, filled(200, 'b')}, {20, 0, 0, filled(200, 'c')}},
                        BlockPoint{0, 0, 0}, R"({"type":"map_shown","n":2})");
  server.publish_blocks({}, std::nullopt, R"({"type":"map_shown","n":3})");
  server.finish();

  std::map<std::array<std::int32_t, 3>, char> held;  // block -> its payload's fill
  std::vector<int> shown;
  std::string message;
  bool binary = false;
  for (;;) {
    ASSERT_FALSE(viewer.read(message, binary)) << "the stream ended without the end message";
    if (binary) {
      ASSERT_EQ(u32_at(message, 0), 0u);
      std::size_t at = 8;
      for (std::uint32_t i = 0; i < u32_at(message, 4); ++i) {
        std::array<std::int32_t, 3> key{};
        std::memcpy(key.data(), message.data() + at, 12);
        held[key] = message[at + 16];
        at += 16 + u32_at(message, at + 12);
      }
      continue;
    }
    const nlohmann::json m = nlohmann::json::parse(message);
    if (m["type"] == "end") break;
    if (m["type"] == "map_round") continue;  // acknowledged by the client
    const int n = m["n"];
    shown.push_back(n);
    using Key = std::array<std::int32_t, 3>;
    if (n == 1) {
      for (std::int32_t x = 0; x < 10; ++x) EXPECT_EQ(held.count(Key{x, 0, 0}), 1u) << x;
    } else {
      EXPECT_EQ((held[Key{5, 0, 0}]), 'b') << "publication " << n << " before its block 5";
      EXPECT_EQ(held.count(Key{20, 0, 0}), 1u) << "publication " << n << " before its block 20";
    }
  }
  // A message due while an older one waited unsent replaces it (the newest stands for both).
  ASSERT_FALSE(shown.empty());
  for (std::size_t i = 1; i < shown.size(); ++i) EXPECT_LT(shown[i - 1], shown[i]);
  EXPECT_EQ(shown.back(), 3);
}

// Appends each block of a binary map batch as (its x, its first payload byte).
void append_batch_blocks(const std::string& message,
                         std::vector<std::pair<std::int32_t, char>>& blocks) {
  std::size_t at = 8;
  for (std::uint32_t i = 0; i < u32_at(message, 4); ++i) {
    std::int32_t x = 0;
    std::memcpy(&x, message.data() + at, 4);
    blocks.emplace_back(x, message[at + 16]);
    at += 16 + u32_at(message, at + 12);
  }
}

/// Reads `client`'s messages until a map round ends; returns the blocks read (fill character of
/// each payload by block x) and the round's number. Fails on anything but blocks, shown
/// messages and the round's end.
std::pair<std::vector<std::pair<std::int32_t, char>>, int> read_round(Client& client) {
  std::vector<std::pair<std::int32_t, char>> blocks;
  std::string message;
  bool binary = false;
  for (;;) {
    if (client.read(message, binary)) {
      ADD_FAILURE() << "the stream ended before the round's end";
      return {blocks, 0};
    }
    if (binary) {
      append_batch_blocks(message, blocks);
      continue;
    }
    const nlohmann::json m = nlohmann::json::parse(message);
    if (m["type"] == "map_round") return {blocks, m["round"].get<int>()};
    EXPECT_EQ(m["type"], "map_shown") << message;
  }
}

TEST(Server, AViewerThatDoesNotAcknowledgeGetsOneRoundThenTheNewestBlocksOnce) {
  ServerConfig config = config_with_page();
  config.chunk_bytes = 256;  // a block or two per batch: a round is many frames
  Server server{config};
  Client viewer(0, /*acknowledge=*/false);
  ASSERT_FALSE(viewer.connect(server.port()));
  for (int i = 0; i < 1000 && server.stats().clients < 1; ++i) std::this_thread::sleep_for(10ms);
  std::vector<MapBlock> first;
  for (std::int32_t x = 0; x < 10; ++x) first.push_back({x, 0, 0, filled(200, 'a')});
  server.publish_blocks(std::move(first), BlockPoint{0, 0, 0}, R"({"type":"map_shown","n":0})");
  auto [round1, n1] = read_round(viewer);
  EXPECT_EQ(n1, 1);
  EXPECT_EQ(round1.size(), 10u);

  // 100 more publications (frames) of blocks 0..14, each with newer payloads, while the viewer
  // has not acknowledged round 1: nothing more is sent, and each block waits once.
  for (int p = 0; p < 100; ++p) {
    std::vector<MapBlock> blocks;
    for (std::int32_t x = 0; x < 15; ++x)
      blocks.push_back({x, 0, 0, filled(200, static_cast<char>('b' + p % 20))});
    server.publish_blocks(std::move(blocks), BlockPoint{0, 0, 0},
                          R"({"type":"map_shown","n":)" + std::to_string(p + 1) + "}");
  }
  std::vector<MapBlock> last;
  for (std::int32_t x = 0; x < 15; ++x) last.push_back({x, 0, 0, filled(200, 'z')});
  server.publish_blocks(std::move(last), BlockPoint{0, 0, 0}, R"({"type":"map_shown","n":101})");
  std::this_thread::sleep_for(300ms);
  const ServerStats s = server.stats();
  EXPECT_EQ(s.blocks_sent, 10u) << "only the unacknowledged round went";
  EXPECT_EQ(s.map_rounds_sent, 1u);
  EXPECT_LE(s.max_client_pending_blocks, 15u) << "the pending set is bounded by the blocks";
  // (Publications the I/O thread had not taken yet merged before reaching the viewer.)
  EXPECT_LE(s.blocks_superseded, 101u * 15u - 15u);

  // Acknowledged: the newest payload of each changed block, once, then one shown message
  // (the newest) and the next round's end.
  ASSERT_FALSE(viewer.write(R"({"type":"map_ack","round":1})"));
  std::vector<std::pair<std::int32_t, char>> blocks;
  std::vector<int> shown;
  std::string message;
  bool binary = false;
  for (;;) {
    ASSERT_FALSE(viewer.read(message, binary));
    if (binary) {
      append_batch_blocks(message, blocks);
      continue;
    }
    const nlohmann::json m = nlohmann::json::parse(message);
    if (m["type"] == "map_round") {
      EXPECT_EQ(m["round"], 2);
      break;
    }
    shown.push_back(m["n"].get<int>());
  }
  std::sort(blocks.begin(), blocks.end());
  std::vector<std::pair<std::int32_t, char>> expected;
  for (std::int32_t x = 0; x < 15; ++x) expected.emplace_back(x, 'z');
  EXPECT_EQ(blocks, expected) << "each block once, its newest payload";
  EXPECT_EQ(shown, (std::vector<int>{101})) << "the newest publication stands for the others";
  EXPECT_EQ(server.stats().map_rounds_acknowledged, 1u);
}

TEST(Server, AMalformedOrUnexpectedAcknowledgementClosesTheConnection) {
  Server server{config_with_page()};
  for (const char* bad :
       {R"({"type":"map_ack","round":1})",  // no round sent yet
        R"({"type":"map_ack","round":"1"})", R"({"type":"map_ack"})",
        R"({"type":"map_ack","round":-1})", R"({"type":"map_ack","round":1.5})"}) {
    Client client(0, /*acknowledge=*/false);
    ASSERT_FALSE(client.connect(server.port()));
    ASSERT_FALSE(client.write(bad));
    EXPECT_NE(client.read_until_closed(), asio::error::timed_out) << bad;
    EXPECT_EQ(client.reason().code, websocket::close_code::policy_error) << bad;
  }
  // A round acknowledged twice.
  server.publish_blocks({{0, 0, 0, filled(10, 'a')}});
  Client twice(0, /*acknowledge=*/false);
  ASSERT_FALSE(twice.connect(server.port()));
  EXPECT_EQ(read_round(twice).second, 1);
  ASSERT_FALSE(twice.write(R"({"type":"map_ack","round":1})"));
  ASSERT_FALSE(twice.write(R"({"type":"map_ack","round":1})"));
  EXPECT_NE(twice.read_until_closed(), asio::error::timed_out);
  EXPECT_EQ(twice.reason().code, websocket::close_code::policy_error);
  EXPECT_EQ(server.stats().clients_closed_bad_message, 6u);
  EXPECT_EQ(server.stats().map_rounds_acknowledged, 1u);
}

TEST(MapPublisher, APacedRunListsFramesAtMostOnceAfterTheirBlocksInOrder) {
  Server server{config_with_page()};
  Client viewer;
  ASSERT_FALSE(viewer.connect(server.port()));
  for (int i = 0; i < 1000 && server.stats().clients < 1; ++i) std::this_thread::sleep_for(10ms);
  const FusionConfig config = fusion_config();
  FusionPipeline pipeline(config, 2);
  MapPublisher publisher(server, kVoxel, config.min_weight, 0.0);
  pipeline.set_integration_observer(
      [&](const TsdfMap& map, const Eigen::Vector3f& sensor, const Frame& frame) {
        publisher.integrated(map, sensor, IntegratedFrame{frame.seq, frame.submitted_s});
      });
  SequenceRunOptions paced;
  paced.rate_hz = 20.0;
  paced.loops = 2;
  const auto sequence = small_depth_sequence();  // 6 frames, twice
  run_sequence(pipeline, *sequence, paced, [](const Frame& f) { ASSERT_TRUE(f.ok()) << f.error; });
  publisher.finish(pipeline.map());
  server.finish();

  std::vector<std::uint64_t> seqs;
  std::vector<double> entered;
  std::string message;
  bool binary = false;
  for (;;) {
    ASSERT_FALSE(viewer.read(message, binary)) << "the stream ended without the end message";
    if (binary) continue;
    const double received_ms =
        1e3 *
        std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
    const nlohmann::json m = nlohmann::json::parse(message);
    if (m["type"] == "end") break;
    if (m["type"] != "map_shown") continue;
    const double meshed = m["meshed_ms"], published = m["published_ms"];
    EXPECT_LE(meshed, published + 1.0);
    EXPECT_LE(published, received_ms + 1.0);
    for (const auto& f : m["frames"]) {
      seqs.push_back(f[0]);
      entered.push_back(f[1]);
      EXPECT_LE(entered.back(), meshed + 1.0) << "frame " << seqs.back();
    }
  }
  // This viewer reads only after the run: the updates it was behind on went as one round,
  // whose message lists the newest publication's frames (serve/server.h: map_round).
  ASSERT_FALSE(seqs.empty());
  for (std::size_t i = 1; i < seqs.size(); ++i)
    EXPECT_LT(seqs[i - 1], seqs[i]) << "each frame at most once, in order";
  EXPECT_EQ(seqs.back(), 11u) << "the last frame is shown";
  // Entry times are the paced schedule's (1 / 20 Hz apart), on the same clock as the others.
  for (std::size_t i = 0; i < entered.size(); ++i)
    EXPECT_NEAR(entered[i] - entered[0], 50.0 * static_cast<double>(seqs[i] - seqs[0]), 1.0) << i;
}

}  // namespace
}  // namespace meshflow::serve
