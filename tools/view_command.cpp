// meshflow view FILE [--serve [HOST:]PORT]: shows a mesh (any format read_mesh() reads) or a .mfc
// file in a browser. The mesh is encoded progressively with meshflow's own codec and streamed by
// the serving layer (serve/server.h) to the page (web/), which decodes it with the same codec
// compiled to WebAssembly: base mesh first, then the vertex-split packets.

#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
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
#include "tools/viewer_server.h"

namespace meshflow::cli {
namespace {

struct ViewOptions {
  std::string input;
  ServeOptions serve;
  float base_ratio = 0.02f;
  std::uint32_t splits_per_packet = 1024;
  std::size_t chunk_kb = 64;
};

void run_view(const ViewOptions& o) {
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

  const std::unique_ptr<serve::Server> served = start_viewer_server(o.serve, o.chunk_kb * 1024);
  serve::Server& server = *served;
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
  server.finish();

  std::printf("meshflow view: %s, %llu vertices, %llu triangles, %zu bytes progressive .mfc",
              o.input.c_str(), static_cast<unsigned long long>(info.vertices),
              static_cast<unsigned long long>(info.triangles), mfc.size());
  if (base_bytes > 0) std::printf(" (base mesh in the first %zu)", base_bytes);
  std::printf("\nurl %s\n", server.url().c_str());
  std::fflush(stdout);

  serve_until_stopped(server, o.serve.exit_after, stdout);
}

}  // namespace

void add_view_options(CLI::App* cmd) {
  auto o = std::make_shared<ViewOptions>();
  cmd->add_option("input", o->input, "Mesh (.ply .obj .off .stl) or compressed mesh (.mfc)")
      ->required()
      ->check(CLI::ExistingFile);
  add_serve_options(cmd, o->serve, "8080");
  cmd->add_option("--base-ratio", o->base_ratio,
                  "Share of the triangles in the base mesh sent first")
      ->check(CLI::Range(0.0f, 1.0f));
  cmd->add_option("--splits-per-packet", o->splits_per_packet,
                  "Vertex splits per packet (the finest step the page can show)")
      ->check(CLI::Range(1u, 1u << 24));
  cmd->add_option("--chunk-kb", o->chunk_kb, "Bytes per WebSocket message, KiB (whole packets)")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1} << 20));
  cmd->callback([o] { run_view(*o); });
}

}  // namespace meshflow::cli
