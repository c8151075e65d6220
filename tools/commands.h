#pragma once
// Subcommands of the meshflow CLI. Each registers its options on `app` and runs when chosen;
// failures throw (meshflow::Error for bad input) and main() maps them to exit codes.

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace meshflow::cli {

void add_reconstruct_command(CLI::App& app);
void add_info_command(CLI::App& app);
void add_demo_command(CLI::App& app);
void add_run_command(CLI::App& app);
void add_profile_command(CLI::App& app);
void add_eval_command(CLI::App& app);
void add_live_command(CLI::App& app);
void add_sample_command(CLI::App& app);
void add_optimize_command(CLI::App& app);

/// Names of the built-in closed objects (`meshflow sample`, `meshflow eval --object`).
std::vector<std::string> closed_object_names();

}  // namespace meshflow::cli
