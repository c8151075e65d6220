// meshflow view FILE [--serve [HOST:]PORT]: shows a mesh (any format read_mesh() reads) or a .mfc
// file in a browser. The mesh is encoded progressively with meshflow's own codec and streamed by
// the serving layer (serve/server.h) to the page (web/), which decodes it with the same codec
// compiled to WebAssembly: base mesh first, then the vertex-split packets. The image is also
// served whole at /mesh.mfc (to download, or to fetch without a WebSocket).

#include <cstdio>
#include <memory>
#include <string>

#include "nodes/compress/progressive_mesh.h"
#include "serve/server.h"
#include "serve/viewer_server.h"
#include "tools/commands.h"
#include "tools/console.h"
#include "tools/run_view.h"
#include "tools/serve_until_stopped.h"

namespace meshflow::cli {
namespace {

struct ViewOptions {
  std::string input;
  ServeOptions serve;
  float base_ratio = serve::view_compress_config().base_ratio;
  std::uint32_t splits_per_packet = serve::view_compress_config().splits_per_packet;
  std::size_t chunk_kb = 64;
};

void run_view(const ViewOptions& o) {
  compress::CompressConfig config = serve::view_compress_config();
  config.base_ratio = o.base_ratio;
  config.splits_per_packet = o.splits_per_packet;
  const serve::ViewImage image = serve::view_image_of_file(o.input, config);
  const auto mfc = std::make_shared<const std::string>(image.mfc.begin(), image.mfc.end());
  const std::unique_ptr<serve::Server> served = serve::start_viewer_server(
      o.serve, o.chunk_kb * 1024, {{"/mesh.mfc", {"application/octet-stream", mfc}}});
  serve::Server& server = *served;
  serve::publish_view(server, image, "meshflow view", o.input);

  std::printf("meshflow view: %s, %llu vertices, %llu triangles, %zu bytes progressive .mfc",
              o.input.c_str(), static_cast<unsigned long long>(image.info.vertices),
              static_cast<unsigned long long>(image.info.triangles), image.mfc.size());
  if (image.base_bytes > 0) std::printf(" (base mesh in the first %zu)", image.base_bytes);
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
