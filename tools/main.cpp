// meshflow: point clouds and depth data to triangle meshes.
// Exit codes: 0 success, 1 runtime error (one line on stderr), 2 usage error.

#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <string>

#include "runtime/process_heap.h"
#include "tools/commands.h"

namespace meshflow::cli {

const std::vector<Command>& commands() {
  static const std::vector<Command> all = {
      {"reconstruct", "Reconstruct a mesh from one point cloud", add_reconstruct_options},
      {"info",
       "Print counts, bounds and fields of a point cloud, statistics of a mesh, or a .mfc header",
       add_info_options},
      {"demo", "Reconstruct a built-in synthetic scene and report speed and accuracy",
       add_demo_options},
      {"run", "Mesh every frame of a recorded sequence through the pipelined graph",
       add_run_options},
      {"profile", "Per-stage timings of a sequence run, with a Chrome trace", add_profile_options},
      {"eval", "Compare a mesh with a reference point cloud or mesh (distances, normals, topology)",
       add_eval_options},
      {"live", "Replay a sequence at a fixed rate through the embedding API; report latency",
       add_live_options},
      {"sample", "Write points sampled uniformly over a built-in closed object (no sensor)",
       add_sample_options},
      {"optimize", "Run the optimisation steps on a mesh (.ply .obj .off .stl .glb) from any tool",
       add_optimize_options},
      {"compress", "Compress a mesh (Edgebreaker or progressive) into a .mfc file",
       add_compress_options},
      {"decompress", "Decode a .mfc file (any level of detail of a progressive one) to a mesh",
       add_decompress_options},
#ifdef MESHFLOW_WITH_SERVE
      {"view",
       "Show a mesh or .mfc file in the browser: served progressively, decoded in WebAssembly",
       add_view_options},
#endif
  };
  return all;
}

}  // namespace meshflow::cli

int main(int argc, char** argv) {
  meshflow::tune_process_heap();  // page faults were a third of a short run
  CLI::App app{"meshflow: fast surface reconstruction from 3D sensor data"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "meshflow " MESHFLOW_VERSION);
  app.option_defaults()->always_capture_default();  // --help shows every option's default
  // Only the chosen subcommand gets its options: registering all of them (about 300 options,
  // each checked against its command's others) took more of a start-up than loading the program.
  // The others are listed by name and description for `meshflow --help`.
  const std::string chosen = argc > 1 ? argv[1] : "";
  for (const meshflow::cli::Command& command : meshflow::cli::commands()) {
    CLI::App* cmd = app.add_subcommand(command.name, command.description);
    if (chosen == command.name) command.add_options(cmd);
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "meshflow: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
