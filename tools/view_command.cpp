// meshflow view FILE [--serve [HOST:]PORT]: shows a mesh (any format read_mesh() reads) or a .mfc
// file in a browser. The mesh is encoded progressively with meshflow's own codec and streamed by
// the serving layer (serve/server.h) to the page (web/), which decodes it with the same codec
// compiled to WebAssembly: base mesh first, then the vertex-split packets.

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "nodes/compress/compressed_mesh.h"
#include "nodes/compress/progressive_mesh.h"
#include "nodes/io/byte_buffer.h"
#include "nodes/io/mesh_readers.h"
#include "runtime/error.h"
#include "runtime/tracing.h"
#include "serve/server.h"
#include "tools/commands.h"
#include "tools/console.h"

#ifndef MESHFLOW_WEB_DIR
#define MESHFLOW_WEB_DIR ""
#endif
#ifndef MESHFLOW_THREE_DIR
#define MESHFLOW_THREE_DIR "/usr/share/javascript/three"
#endif

namespace meshflow::cli {
namespace {

struct ViewOptions {
  std::string input;
  std::string serve = "8080";
  double exit_after = 0.0;
  float base_ratio = 0.02f;
  std::uint32_t splits_per_packet = 1024;
  std::size_t chunk_kb = 64;
  std::size_t max_clients = 8;
  double rate_mbit = 0.0;
};

std::atomic<bool> g_stop{false};

extern "C" void on_stop_signal(int) { g_stop = true; }

/// The page's files: the fixed set the server answers, read once at start from the folders
/// fixed when meshflow was configured (the build's web/ output and Debian's libjs-three). A
/// request path is only ever a key of this map.
std::map<std::string, serve::StaticResource> page_resources() {
  const std::string web = MESHFLOW_WEB_DIR, three = MESHFLOW_THREE_DIR;
  struct File {
    const char* path;
    std::string file;
    const char* type;
  };
  const std::vector<File> files = {
      {"/", web + "/index.html", "text/html; charset=utf-8"},
      {"/viewer.js", web + "/viewer.js", "text/javascript; charset=utf-8"},
      {"/mfc_decoder.js", web + "/mfc_decoder.js", "text/javascript; charset=utf-8"},
      {"/mfc_decoder.wasm", web + "/mfc_decoder.wasm", "application/wasm"},
      {"/three/build/three.module.js", three + "/three.module.js",
       "text/javascript; charset=utf-8"},
      {"/three/examples/jsm/controls/OrbitControls.js",
       three + "/examples/jsm/controls/OrbitControls.js", "text/javascript; charset=utf-8"},
  };
  std::map<std::string, serve::StaticResource> resources;
  for (const File& f : files) {
    std::ifstream in(f.file, std::ios::binary);
    if (!in)
      throw Error(f.file, "viewer page",
                  "a readable file (the page is built into " + web +
                      "; three.js comes from Debian's libjs-three)");
    resources[f.path] = {f.type,
                         std::make_shared<const std::string>(std::istreambuf_iterator<char>(in),
                                                             std::istreambuf_iterator<char>())};
  }
  return resources;
}

void run_view(const ViewOptions& o) {
  const serve::ServeAddress address = serve::parse_serve_address(o.serve);  // before any work
  const double t0 = monotonic_seconds();
  compress::CompressConfig config;
  config.base_ratio = o.base_ratio;
  config.splits_per_packet = o.splits_per_packet;
  std::vector<unsigned char> mfc;
  double read_s = 0.0, encode_s = 0.0;
  std::size_t base_bytes = 0;
  if (is_compressed_mesh_file(o.input)) {
    mfc = io::read_file_bytes(o.input);
    const compress::CompressedMeshInfo info = compress::compressed_mesh_info(mfc, o.input);
    read_s = monotonic_seconds() - t0;
    if (info.kind != compress::CompressionKind::kProgressive) {
      // A single-rate file is decoded and re-encoded progressively, so the page sees a picture
      // from the first bytes.
      const TriangleMesh mesh = compress::decompress_mesh(mfc, o.input);
      const double t1 = monotonic_seconds();
      compress::CompressReport r;
      mfc = compress::compress_progressive(mesh, config, &r);
      base_bytes = r.base_bytes;
      encode_s = monotonic_seconds() - t1;
    }
  } else {
    const TriangleMesh mesh = io::read_mesh(o.input);
    read_s = monotonic_seconds() - t0;
    if (mesh.triangles.empty()) throw Error(o.input, "triangles", "a mesh with triangles");
    const double t1 = monotonic_seconds();
    compress::CompressReport r;
    mfc = compress::compress_progressive(mesh, config, &r);
    base_bytes = r.base_bytes;
    encode_s = monotonic_seconds() - t1;
  }
  const compress::CompressedMeshInfo info = compress::compressed_mesh_info(mfc, o.input);

  serve::ServerConfig server_config;
  server_config.host = address.host;
  server_config.port = address.port;
  server_config.max_clients = o.max_clients;
  server_config.client_megabits_per_second = o.rate_mbit;
  server_config.chunk_bytes = o.chunk_kb * 1024;
  server_config.resources = page_resources();
  serve::Server server(std::move(server_config));
  server.publish_mesh(mfc);
  server.publish_stats(
      nlohmann::json{{"type", "stats"},
                     {"source", "meshflow view"},
                     {"file", o.input},
                     {"vertices", info.vertices},
                     {"triangles", info.triangles},
                     {"mfc_bytes", mfc.size()},
                     {"stages_ms", {{"read", 1e3 * read_s}, {"encode", 1e3 * encode_s}}}}
          .dump());

  std::printf("meshflow view: %s, %llu vertices, %llu triangles, %zu bytes progressive .mfc",
              o.input.c_str(), static_cast<unsigned long long>(info.vertices),
              static_cast<unsigned long long>(info.triangles), mfc.size());
  if (base_bytes > 0) std::printf(" (base mesh in the first %zu)", base_bytes);
  std::printf("\nurl %s\n", server.url().c_str());
  std::fflush(stdout);

  g_stop = false;
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  const double start = monotonic_seconds();
  while (!g_stop && (o.exit_after <= 0.0 || monotonic_seconds() - start < o.exit_after))
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const serve::ServerStats s = server.stats();
  std::printf("served %llu viewers, %llu frames, %llu bytes (%llu frames dropped)\n",
              static_cast<unsigned long long>(s.clients_accepted),
              static_cast<unsigned long long>(s.frames_sent),
              static_cast<unsigned long long>(s.bytes_sent),
              static_cast<unsigned long long>(s.frames_dropped));
  std::fflush(stdout);
}

}  // namespace

void add_view_options(CLI::App* cmd) {
  auto o = std::make_shared<ViewOptions>();
  cmd->add_option("input", o->input, "Mesh (.ply .obj .off .stl) or compressed mesh (.mfc)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--serve", o->serve,
                  "Where to serve the page: [HOST:]PORT (HOST 127.0.0.1 unless given; port 0: "
                  "any free port; the URL is printed)");
  cmd->add_option("--exit-after", o->exit_after,
                  "Stop serving after this many seconds (0: until Ctrl-C)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--base-ratio", o->base_ratio,
                  "Share of the triangles in the base mesh sent first")
      ->check(CLI::Range(0.0f, 1.0f));
  cmd->add_option("--splits-per-packet", o->splits_per_packet,
                  "Vertex splits per packet (the finest step the page can show)")
      ->check(CLI::Range(1u, 1u << 24));
  cmd->add_option("--chunk-kb", o->chunk_kb, "Bytes per WebSocket message, KiB (whole packets)")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1} << 20));
  cmd->add_option("--max-viewers", o->max_clients, "Browsers connected at once")
      ->check(CLI::Range(std::size_t{1}, std::size_t{256}));
  cmd->add_option("--serve-rate", o->rate_mbit,
                  "Cap each viewer's bandwidth, Mbit/s (0: none): how a narrow link feels")
      ->check(CLI::NonNegativeNumber);
  cmd->callback([o] { run_view(*o); });
}

}  // namespace meshflow::cli
