// The viewer of a run (tools/run_view.h) with the serving layer, and serve_until_stopped()
// (tools/serve_until_stopped.h).

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "runtime/error.h"
#include "runtime/tracing.h"
#include "serve/map_publisher.h"
#include "serve/run_publisher.h"
#include "serve/viewer_server.h"
#include "tools/run_view.h"
#include "tools/serve_until_stopped.h"

namespace meshflow::cli {
namespace {

std::atomic<bool> g_stop{false};

extern "C" void on_stop_signal(int) { g_stop = true; }

class ServedRunView final : public RunView {
 public:
  ServedRunView(const ServeOptions& options, const std::string& source)
      : options_(options),
        server_(serve::start_viewer_server(options)),
        publisher_(*server_, source) {
    std::fprintf(stderr, "url %s\n", server_->url().c_str());
    std::fflush(stderr);
  }

  void frame(const Frame& f, bool with_mesh) override { publisher_.frame(f, with_mesh); }
  void frame(const LiveResult& result) override { publisher_.frame(result); }
  void result(const TriangleMesh& mesh, const Eigen::Vector3d& origin,
              const std::vector<unsigned char>& encoded) override {
    publisher_.result(mesh, origin, serve::MeshCoding::kProgressive, encoded);
  }
  std::function<void(const TsdfMap&, const Eigen::Vector3f&, const Frame&)> map_observer(
      float voxel_size, float min_weight) override {
    map_ = std::make_unique<serve::MapPublisher>(*server_, voxel_size, min_weight);
    return [map = map_.get()](const TsdfMap& volume, const Eigen::Vector3f& sensor,
                              const Frame& frame) {
      map->integrated(volume, sensor, serve::IntegratedFrame{frame.seq, frame.submitted_s});
    };
  }
  void map_result(const TsdfMap& map) override {
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

void serve_until_stopped(const serve::Server& server, double exit_after, std::FILE* out) {
  std::fflush(stdout);  // the run's report (--json's summary) readable while it serves
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
