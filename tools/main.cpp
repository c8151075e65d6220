// meshflow: point clouds and depth data to triangle meshes.
// Exit codes: 0 success, 1 runtime error (one line on stderr), 2 usage error.

#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>

#include "tools/commands.h"

int main(int argc, char** argv) {
  CLI::App app{"meshflow: fast surface reconstruction from 3D sensor data"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "meshflow " MESHFLOW_VERSION);
  app.option_defaults()->always_capture_default();  // --help shows every option's default
  meshflow::cli::add_reconstruct_command(app);
  meshflow::cli::add_info_command(app);
  meshflow::cli::add_demo_command(app);
  meshflow::cli::add_run_command(app);
  meshflow::cli::add_profile_command(app);
  meshflow::cli::add_eval_command(app);
  meshflow::cli::add_live_command(app);
  meshflow::cli::add_sample_command(app);
  meshflow::cli::add_optimize_command(app);
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
