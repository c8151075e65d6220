#pragma once
// Subcommands of the meshflow CLI. Each add_*_options registers a subcommand's options and its
// callback on `cmd` (created by main() with the command's name and description); the callback
// runs when the command is chosen. Failures throw (meshflow::Error for bad input) and main()
// maps them to exit codes.

#include <CLI/CLI.hpp>

#include "graph/chunked_reconstruction.h"
#include "graph/reconstruction_config.h"

#include <string>
#include <vector>

namespace meshflow::cli {

void add_reconstruct_options(CLI::App* cmd);
void add_info_options(CLI::App* cmd);
void add_demo_options(CLI::App* cmd);
void add_run_options(CLI::App* cmd);
void add_profile_options(CLI::App* cmd);
void add_eval_options(CLI::App* cmd);
void add_live_options(CLI::App* cmd);
void add_sample_options(CLI::App* cmd);
void add_optimize_options(CLI::App* cmd);
void add_compress_options(CLI::App* cmd);
void add_decompress_options(CLI::App* cmd);
void add_view_options(CLI::App* cmd);  // with the serving layer (MESHFLOW_WITH_SERVE)

/// Whether `path` names a meshflow compressed mesh (.mfc).
bool is_compressed_mesh_file(const std::string& path);
/// Registers --compress edgebreaker|progressive on `cmd` (reconstruct, run), into `method`.
void add_compress_option(CLI::App* cmd, std::string& method);
/// The pipeline's compression for a --compress value ("" = none) and an output path: a .mfc
/// output without --compress means Edgebreaker.
MeshCompression compression_for(const std::string& method, const std::string& output);
/// Whether `meshflow info` reads `path` as a mesh: .obj .off .stl .glb, or a .ply whose header
/// declares faces (a PLY without faces is a point cloud). Throws Error on an unreadable PLY.
bool is_mesh_info_file(const std::string& path);
/// `meshflow info` on a mesh: mesh_statistics() printed (or --json). Throws Error.
void run_mesh_info(const std::string& path);
/// `meshflow info` on a compressed mesh: its header (and --json). Throws Error.
void run_compressed_info(const std::string& path);

/// `reconstruct --chunk`: the out-of-core path (graph/chunked_reconstruction.h) from `input` to
/// the mesh file `output` and, when `tiles_dir` is not empty, its tiles there
/// (nodes/chunk/mesh_tiles.h), with its report (or --json document). Throws meshflow::Error.
void run_chunked_reconstruct(const std::string& input, const std::string& columns,
                             const std::string& output, const std::string& tiles_dir,
                             const ReconstructionConfig& config, const ChunkingConfig& chunking,
                             int threads);

struct Command {
  const char* name;
  const char* description;
  void (*add_options)(CLI::App* cmd);
};

/// Every subcommand, in the order `meshflow --help` lists them.
const std::vector<Command>& commands();

/// Names of the built-in closed objects (`meshflow sample`, `meshflow eval --object`).
std::vector<std::string> closed_object_names();

}  // namespace meshflow::cli
