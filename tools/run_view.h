#pragma once
// --serve on the commands that make meshes (view, reconstruct, run, live): the options, and a
// viewer of a run that feeds the serving layer (serve/run_publisher.h) and keeps serving the
// result afterwards. The options are the option model's (options/serve_options.h), shared with
// the Python module. Without the serving layer (-DMESHFLOW_SERVE=OFF or no Boost) --serve is
// still accepted by the parser and fails with a message saying so (tools/run_view_off.cpp).

#include <CLI/CLI.hpp>

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "graph/frame.h"
#include "graph/live_pipeline.h"
#include "nodes/fusion/tsdf_volume.h"
#include "options/serve_options.h"

namespace meshflow::cli {

/// The serving options of the option model (options/serve_options.h): --serve's address is
/// checked when the command line is parsed (a usage error, exit 2, before any input is read).
using ServeOptions = options::ServeOptions;

/// Registers the option model's serving options (--serve, --serve-rate, --exit-after,
/// --max-viewers) on `cmd`, checked by the model when parsed. With
/// `address_default` (view), --serve has that default; otherwise (run, live, reconstruct) the
/// server starts only when --serve is given and the other three need it.
void add_serve_options(CLI::App* cmd, ServeOptions& options, const char* address_default = nullptr);

/// What a run shows its viewers. Called from the run's sink thread (one call at a time); no call
/// waits on the network.
class RunView {
 public:
  virtual ~RunView() = default;
  /// A delivered frame: its stats, and with `with_mesh` its mesh (newest only, single-rate).
  virtual void frame(const Frame& f, bool with_mesh) = 0;
  /// A frame of `meshflow live`.
  virtual void frame(const LiveResult& result) = 0;
  /// The run's final mesh (progressive; `encoded` a ready .mfc image of it, or empty).
  virtual void result(const TriangleMesh& mesh, const Eigen::Vector3d& origin,
                      const std::vector<unsigned char>& encoded) = 0;
  /// A fused run: the observer for FusionPipeline::set_integration_observer, which sends the
  /// map's changed blocks as it grows (serve/map_publisher.h), for a map of `voxel_size` metres
  /// meshed with `min_weight`.
  virtual std::function<void(const TsdfMap&, const Eigen::Vector3f&, const Frame&)> map_observer(
      float voxel_size, float min_weight) = 0;
  /// After a fused run (map_observer() given): the map's blocks changed since the last update.
  virtual void map_result(const TsdfMap& map) = 0;
  /// After the run's files and report: publishes the last mesh and the end of the run, then
  /// serves until Ctrl-C or --exit-after seconds, and prints what was served (stderr).
  virtual void finish_and_serve() = 0;
};

/// The view of a run named `source` when --serve was given (the server started, its URL printed
/// on stderr as "url URL"), else nullptr. Throws meshflow::Error for a bad address or an address
/// in use, or when this meshflow was built without the serving layer.
std::unique_ptr<RunView> start_run_view(const ServeOptions& options, const std::string& source);

}  // namespace meshflow::cli
