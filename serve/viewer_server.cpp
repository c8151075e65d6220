// The viewer's server (serve/viewer_server.h): the page's files, the server on the serving
// options, and a finished mesh published as `meshflow view` shows it.

#include "serve/viewer_server.h"

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <utility>

#include "nodes/compress/progressive_mesh.h"
#include "nodes/io/byte_buffer.h"
#include "nodes/io/mesh_readers.h"
#include "nodes/io/parse_util.h"
#include "runtime/error.h"
#include "runtime/tracing.h"

#ifndef MESHFLOW_WEB_DIR
#define MESHFLOW_WEB_DIR ""
#endif
#ifndef MESHFLOW_WEB_INSTALL_DIR
#define MESHFLOW_WEB_INSTALL_DIR ""
#endif
#ifndef MESHFLOW_THREE_DIR
#define MESHFLOW_THREE_DIR "/usr/share/javascript/three"
#endif

namespace meshflow::serve {
namespace {

/// The page's files: the fixed set the server answers, read once at start from
/// viewer_page_folder() and Debian's libjs-three. A request path is only ever a key of this map.
std::map<std::string, StaticResource> viewer_page_resources() {
  const std::string web = viewer_page_folder(), three = MESHFLOW_THREE_DIR;
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
  std::map<std::string, StaticResource> resources;
  for (const File& f : files) {
    std::ifstream in(f.file, std::ios::binary);
    if (!in)
      throw Error(f.file, "viewer page",
                  "a readable file (the page's folder is $MESHFLOW_WEB_DIR when set, else the "
                  "build's " MESHFLOW_WEB_DIR " or the installed " MESHFLOW_WEB_INSTALL_DIR
                  "; three.js comes from Debian's libjs-three)");
    resources[f.path] = {f.type,
                         std::make_shared<const std::string>(std::istreambuf_iterator<char>(in),
                                                             std::istreambuf_iterator<char>())};
  }
  return resources;
}

bool has_viewer_page(const std::string& folder) {
  return !folder.empty() && std::ifstream(folder + "/index.html").good();
}

}  // namespace

std::string viewer_page_folder() {
  if (const char* env = std::getenv("MESHFLOW_WEB_DIR"); env != nullptr && *env != '\0') return env;
  if (has_viewer_page(MESHFLOW_WEB_DIR)) return MESHFLOW_WEB_DIR;
  if (has_viewer_page(MESHFLOW_WEB_INSTALL_DIR)) return MESHFLOW_WEB_INSTALL_DIR;
  return MESHFLOW_WEB_DIR;  // named in the error when nothing is found
}

std::unique_ptr<Server> start_viewer_server(const options::ServeOptions& o, std::size_t chunk_bytes,
                                            std::map<std::string, StaticResource> extra) {
  options::validate(o);
  const options::ServeAddress address = options::parse_serve_address(o.address);
  ServerConfig config;
  config.host = address.host;
  config.port = address.port;
  config.max_clients = o.max_viewers;
  config.client_megabits_per_second = o.rate_mbit;
  config.chunk_bytes = chunk_bytes;
  config.resources = viewer_page_resources();
  for (auto& [path, resource] : extra) config.resources[path] = std::move(resource);
  return std::make_unique<Server>(std::move(config));
}

compress::CompressConfig view_compress_config() {
  compress::CompressConfig config;
  config.base_ratio = 0.02f;
  config.splits_per_packet = 1024;
  return config;
}

ViewImage view_image_of_mesh(const TriangleMesh& mesh, const compress::CompressConfig& config,
                             const std::string& name) {
  if (mesh.triangles.empty()) throw Error(name, "triangles", "a mesh with triangles");
  ViewImage image;
  const double t0 = monotonic_seconds();
  compress::CompressReport report;
  image.mfc = compress::compress_progressive(mesh, config, &report);
  image.single_rate = compress::compress_mesh(mesh, config);
  image.base_bytes = report.base_bytes;
  image.encode_s = monotonic_seconds() - t0;
  image.info = compress::compressed_mesh_info(image.mfc, name);
  return image;
}

ViewImage view_image_of_file(const std::string& path, const compress::CompressConfig& config) {
  const double t0 = monotonic_seconds();
  ViewImage image;
  if (io::lower_extension(path) == ".mfc") {
    std::vector<unsigned char> mfc = io::read_file_bytes(path);
    const compress::CompressedMeshInfo info = compress::compressed_mesh_info(mfc, path);
    const double read_s = monotonic_seconds() - t0;
    if (info.kind == compress::CompressionKind::kProgressive) {
      const double t1 = monotonic_seconds();
      compress::CompressConfig same = config;
      same.step = info.quantizer.step;  // the file's quantisation: no second rounding
      image.single_rate = compress::compress_mesh(compress::decompress_mesh(mfc, path), same);
      image.encode_s = monotonic_seconds() - t1;
      image.mfc = std::move(mfc);
      image.info = info;
    } else {
      // A single-rate file is decoded and re-encoded progressively, so the page sees a picture
      // from the first bytes; the file itself follows the base on a fast link.
      image = view_image_of_mesh(compress::decompress_mesh(mfc, path), config, path);
      image.single_rate = std::move(mfc);
    }
    image.read_s = read_s;
    return image;
  }
  const TriangleMesh mesh = io::read_mesh(path);
  const double read_s = monotonic_seconds() - t0;
  image = view_image_of_mesh(mesh, config, path);
  image.read_s = read_s;
  return image;
}

void publish_view(Server& server, const ViewImage& image, const std::string& source,
                  const std::string& file) {
  server.publish_mesh(image.mfc, image.single_rate);
  server.publish_stats(nlohmann::json{
      {"type", "stats"},
      {"source", source},
      {"file", file},
      {"vertices", image.info.vertices},
      {"triangles", image.info.triangles},
      {"mfc_bytes", image.mfc.size()},
      {"stages_ms", {{"read", 1e3 * image.read_s}, {"encode", 1e3 * image.encode_s}}}}
                           .dump());
  server.finish();
}

}  // namespace meshflow::serve
