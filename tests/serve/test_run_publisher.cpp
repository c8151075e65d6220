// The sink between a run and the server (serve/run_publisher.h): meshes are encoded only while
// someone watches, the newest replaces older ones not yet encoded, finish() publishes the last
// mesh whoever watches and ends the stream, and a viewer that never reads costs the sink nothing
// but dropped frames (asserted on the counters, not on timing).

#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "nodes/compress/compressed_mesh.h"
#include "serve/run_publisher.h"
#include "serve/server.h"
#include "tests/serve/test_client.h"

namespace meshflow::serve {
namespace {

using namespace std::chrono_literals;
using testing::Client;
using testing::config_with_page;
using testing::wavy_grid;

Frame frame_with_mesh(std::size_t index, const TriangleMesh& mesh) {
  Frame f;
  f.source_index = index;
  f.mesh = mesh;
  StageRecord read;
  read.stage = "read";
  read.end_s = 0.002;
  f.timings = {read, read};
  return f;
}

/// Reads until the end message; the last mesh header, stats and the bytes of that mesh.
struct Stream {
  nlohmann::json header, stats;
  std::size_t bytes = 0;            ///< of the image that came whole
  std::vector<unsigned char> data;  ///< the last mesh's whole image (single-rate after a base)
};
Stream read_to_end(Client& client) {
  Stream s;
  std::string message;
  bool binary = false;
  for (;;) {
    if (client.read(message, binary)) {
      ADD_FAILURE() << "the stream ended without the end message";
      return s;
    }
    if (binary) {
      // With "refine":"single_rate" the base of the progressive image comes first, then the
      // single-rate image (ids with the high bit): that one is the whole mesh.
      const bool single = (static_cast<unsigned char>(message[3]) & 0x80u) != 0;
      if (single && s.header["refine"] == "single_rate" && s.bytes == s.header["base_end"]) {
        s.bytes = 0;
        s.data.clear();
      }
      s.bytes += message.size() - 8;
      s.data.insert(s.data.end(), message.begin() + 8, message.end());
      continue;
    }
    const nlohmann::json doc = nlohmann::json::parse(message);
    if (doc["type"] == "end") return s;
    if (doc["type"] == "mesh") {
      s.header = doc;
      s.bytes = 0;
      s.data.clear();
    }
    if (doc["type"] == "stats") s.stats = doc;
  }
}

TEST(RunPublisher, EncodesNothingWithoutViewersUntilTheRunEnds) {
  Server server{config_with_page()};
  RunPublisher publisher(server, "test run");
  for (std::uint32_t i = 0; i < 5; ++i)
    publisher.frame(frame_with_mesh(i, wavy_grid(10 + i)), true);
  std::this_thread::sleep_for(300ms);  // the encoder looks for viewers every 100 ms
  EXPECT_EQ(publisher.counts().meshes_encoded, 0u);
  EXPECT_EQ(publisher.counts().meshes_replaced, 4u);
  EXPECT_EQ(server.stats().meshes_published, 0u);
  publisher.finish();
  EXPECT_EQ(publisher.counts().meshes_encoded, 1u);
  EXPECT_EQ(publisher.counts().frames, 5u);

  Client late;  // after the run: the last frame's mesh, the final stats, the end
  ASSERT_FALSE(late.connect(server.port()));
  const Stream s = read_to_end(late);
  EXPECT_EQ(s.header["triangles"], 2 * 13 * 13);
  EXPECT_EQ(s.header["kind"], "edgebreaker");
  EXPECT_EQ(s.bytes, s.header["bytes"].get<std::size_t>());
  EXPECT_EQ(s.stats["state"], "finished");
  EXPECT_EQ(s.stats["frames"], 5);
  EXPECT_EQ(s.stats["source"], "test run");
}

TEST(RunPublisher, TheResultIsProgressiveInWorldCoordinates) {
  Server server{config_with_page()};
  RunPublisher publisher(server, "test");
  publisher.result(wavy_grid(30), Eigen::Vector3d(100.0, 0.0, 0.0));
  publisher.finish();
  Client client;
  ASSERT_FALSE(client.connect(server.port()));
  const Stream s = read_to_end(client);
  EXPECT_EQ(s.header["kind"], "progressive");
  EXPECT_EQ(s.header["refine"], "single_rate") << "no cap: the base, then the single-rate image";
  EXPECT_EQ(s.bytes, s.header["single_rate_bytes"].get<std::size_t>());
  EXPECT_EQ(s.header["vertices"], 30 * 30);
  const TriangleMesh decoded = compress::decompress_mesh(s.data, "stream");
  ASSERT_EQ(decoded.vertices.size(), 30u * 30u);
  float min_x = 1e9f;
  for (const Eigen::Vector3f& v : decoded.vertices) min_x = std::min(min_x, v.x());
  EXPECT_NEAR(min_x, 100.0f, 1e-3f) << "the origin was added";
}

TEST(RunPublisher, NothingIsEncodedForAViewerThatStoppedReading) {
  // A viewer that stopped reading holds its last mesh's frames (ServerStats::
  // clients_ready_for_mesh is 0): the encoder then takes no core from the run, only the last
  // mesh is encoded at the end.
  const TriangleMesh mesh = wavy_grid(240, 0.05f);
  const std::vector<unsigned char> mfc = compress::compress_mesh(mesh);
  Server server{config_with_page()};
  Client stalled(4096);
  ASSERT_FALSE(stalled.connect(server.port()));
  for (int i = 0; i < 1000 && server.stats().clients < 1; ++i) std::this_thread::sleep_for(10ms);
  // 10 MB of meshes, published apart (not replaced by each other before they are written):
  // more than the kernel's buffers take with a 4 kB receive buffer.
  for (int i = 0; i < 200; ++i) {
    server.publish_mesh(mfc);
    std::this_thread::sleep_for(2ms);
  }
  std::this_thread::sleep_for(200ms);
  ASSERT_EQ(server.stats().clients_ready_for_mesh, 0u);
  RunPublisher publisher(server, "test");
  const Frame f = frame_with_mesh(0, mesh);
  for (int i = 0; i < 30; ++i) {
    publisher.frame(f, true);
    std::this_thread::sleep_for(10ms);  // the encoder looks every 20 ms
  }
  EXPECT_EQ(publisher.counts().meshes_encoded, 0u);
  EXPECT_EQ(publisher.counts().meshes_replaced, 29u);
  publisher.finish();
  EXPECT_EQ(publisher.counts().meshes_encoded, 1u);
}

TEST(RunPublisher, AViewerThatNeverReadsCostsTheSinkOnlyDroppedFrames) {
  // 200 frames of a 50+ kB mesh to a viewer with a 4 kB receive buffer that never reads: every
  // frame is stats plus a mesh offer; what the viewer cannot take is dropped, its queue stays
  // at one mesh, and a viewer that reads gets the last frame when the run ends.
  const TriangleMesh mesh = wavy_grid(240, 0.05f);
  ASSERT_GT(compress::compress_mesh(mesh).size(), 50'000u);
  Server server{config_with_page()};
  Client stalled(4096);
  ASSERT_FALSE(stalled.connect(server.port()));
  for (int i = 0; i < 1000 && server.stats().clients < 1; ++i) std::this_thread::sleep_for(10ms);
  RunPublisher publisher(server, "test");
  const Frame f = frame_with_mesh(0, mesh);
  for (std::size_t i = 0; i < 200; ++i) publisher.frame(f, true);
  publisher.finish();
  const RunPublisherCounts c = publisher.counts();
  EXPECT_EQ(c.frames, 200u);
  EXPECT_EQ(c.meshes_offered, 200u);
  EXPECT_EQ(c.meshes_encoded + c.meshes_replaced + c.encode_errors, 200u);
  EXPECT_EQ(c.encode_errors, 0u);
  EXPECT_GT(c.meshes_replaced, 0u) << "frames offered faster than encoded are replaced";
  const ServerStats s = server.stats();
  // (Server-side dropping for a stalled viewer is Server.AClientThatNeverReadsDoesNotBlock-
  // Publishing's: here few meshes may reach the server, and the kernel's socket buffers can
  // hold them all, under a sanitizer's slow encoder especially.)
  // One mesh (header + one chunk: a single-rate image under 64 kB... or a few chunks), one
  // stats message and the frame being written.
  const std::size_t chunks = compress::compress_mesh(mesh).size() / (64 * 1024) + 1;
  EXPECT_LE(s.max_client_queue_frames, chunks + 3);

  Client reader;
  ASSERT_FALSE(reader.connect(server.port()));
  const Stream r = read_to_end(reader);
  EXPECT_EQ(r.header["triangles"], mesh.triangles.size());
  EXPECT_EQ(r.stats["frames"], 200);
}

}  // namespace
}  // namespace meshflow::serve
