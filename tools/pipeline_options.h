#pragma once
// Command-line options that configure the reconstruction stages, shared by the subcommands:
// the option model's table registered with CLI11, and the CLI-only triangulation and sequence
// arguments.

#include <CLI/CLI.hpp>

#include <cstddef>
#include <memory>
#include <string>

#include "graph/reconstruction_config.h"
#include "nodes/io/sequence.h"
#include "options/pipeline_options.h"

namespace meshflow::cli {

/// The option model's settings (options/pipeline_options.h): the CLI registers its table.
using PipelineOptions = options::PipelineOptions;

/// Registers every option of the model (options::pipeline_option_specs()) on `cmd` as --NAME,
/// writing into `options`; values are checked by the model's checks (a usage error, exit 2,
/// with the model's message); help shows what a sentinel default means.
void add_pipeline_options(CLI::App* cmd, PipelineOptions& options);

/// Per-frame depth-map triangulation instead of the volumetric stages (run, profile, live).
struct TriangulationOptions {
  std::string method;  ///< "" (volumetric stages), "naive" or "rqt"
  float rqt_error = QuadtreeConfig{}.error_per_depth2;
  float rqt_noise_multiple = QuadtreeConfig{}.noise_multiple;
  float decimate = 0.0f;  ///< QEM to this share of each frame's triangles (0 = off)

  bool enabled() const { return !method.empty(); }
  /// Writes the method, quadtree thresholds and decimation into `config.triangulation`.
  void apply(ReconstructionConfig& config) const;
};

/// Registers --triangulate --rqt-error --rqt-noise-multiple --decimate on `cmd`.
void add_triangulation_options(CLI::App* cmd, TriangulationOptions& options);

/// The SEQUENCE argument of run/profile: a path, or the built-in synthetic sequence.
struct SequenceArgument {
  std::string path;
  bool synthetic = false;        ///< built-in laser-scan sequence
  bool synthetic_depth = false;  ///< built-in depth-camera sequence
  int synthetic_frames = 8;      ///< frames of either built-in sequence
  std::string synthetic_size;    ///< depth camera WxH; empty: 640x480
  std::size_t in_flight = 2;
  std::size_t every = 1;
  std::size_t max_frames = 0;
};

/// Registers SEQUENCE, --synthetic, --synthetic-depth, --synthetic-frames, --synthetic-size,
/// --in-flight, --every and --max-frames on `cmd`.
void add_sequence_options(CLI::App* cmd, SequenceArgument& argument);

/// Opens the sequence the user named; throws meshflow::Error (or CLI::ValidationError when
/// neither a path nor --synthetic was given).
std::unique_ptr<io::Sequence> open_sequence_argument(const SequenceArgument& argument);

}  // namespace meshflow::cli
