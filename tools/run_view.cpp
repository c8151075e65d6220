// The viewer of a run (tools/run_view.h) and the viewer's server (tools/viewer_server.h), with
// the serving layer.

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "runtime/error.h"
#include "runtime/tracing.h"
#include "serve/map_publisher.h"
#include "serve/run_publisher.h"
#include "tools/viewer_server.h"

#ifndef MESHFLOW_WEB_DIR
#define MESHFLOW_WEB_DIR ""
#endif
#ifndef MESHFLOW_THREE_DIR
#define MESHFLOW_THREE_DIR "/usr/share/javascript/three"
#endif

namespace meshflow::cli {
namespace {

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

class ServedRunView final : public RunView {
 public:
  ServedRunView(const ServeOptions& options, const std::string& source)
      : options_(options), server_(start_viewer_server(options)), publisher_(*server_, source) {
    std::fprintf(stderr, "url %s\n", server_->url().c_str());
    std::fflush(stderr);
  }

  void frame(const Frame& f, bool with_mesh) override { publisher_.frame(f, with_mesh); }
  void frame(const LiveResult& result) override { publisher_.frame(result); }
  void result(const TriangleMesh& mesh, const Eigen::Vector3d& origin,
              const std::vector<unsigned char>& encoded) override {
    publisher_.result(mesh, origin, serve::MeshCoding::kProgressive, encoded);
  }
  std::function<void(const TsdfVolume&, const Eigen::Vector3f&)> map_observer(
      float voxel_size, float min_weight) override {
    map_ = std::make_unique<serve::MapPublisher>(*server_, voxel_size, min_weight);
    return [map = map_.get()](const TsdfVolume& volume, const Eigen::Vector3f& sensor) {
      map->integrated(volume, sensor);
    };
  }
  void map_result(const TsdfVolume& map) override {
    if (map_) map_->finish(map);
  }
  void finish_and_serve() override {
    publisher_.finish();
    serve_until_stopped(*server_, options_.exit_after, stderr);
  }

 private:
  ServeOptions options_;
  std::unique_ptr<serve::Server> server_;
  serve::RunPublisher publisher_;
  std::unique_ptr<serve::MapPublisher> map_;
};

}  // namespace

std::unique_ptr<serve::Server> start_viewer_server(const ServeOptions& o, std::size_t chunk_bytes) {
  const options::ServeAddress address = options::parse_serve_address(o.address);
  serve::ServerConfig config;
  config.host = address.host;
  config.port = address.port;
  config.max_clients = o.max_viewers;
  config.client_megabits_per_second = o.rate_mbit;
  config.chunk_bytes = chunk_bytes;
  config.resources = page_resources();
  return std::make_unique<serve::Server>(std::move(config));
}

void serve_until_stopped(const serve::Server& server, double exit_after, std::FILE* out) {
  g_stop = false;
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  const double start = monotonic_seconds();
  while (!g_stop && (exit_after <= 0.0 || monotonic_seconds() - start < exit_after))
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  const serve::ServerStats s = server.stats();
  std::fprintf(out, "served %llu viewers, %llu frames, %llu bytes (%llu frames dropped)\n",
               static_cast<unsigned long long>(s.clients_accepted),
               static_cast<unsigned long long>(s.frames_sent),
               static_cast<unsigned long long>(s.bytes_sent),
               static_cast<unsigned long long>(s.frames_dropped));
  std::fflush(out);
}

std::unique_ptr<RunView> start_run_view(const ServeOptions& options, const std::string& source) {
  if (!options.enabled()) return nullptr;
  return std::make_unique<ServedRunView>(options, source);
}

}  // namespace meshflow::cli
