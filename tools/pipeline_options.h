#pragma once
// Command-line options that configure the reconstruction stages, shared by the subcommands.

#include <CLI/CLI.hpp>

#include <cstddef>
#include <memory>
#include <string>

#include "graph/frame.h"
#include "nodes/io/sequence.h"

namespace meshflow::cli {

struct PipelineOptions {
  float voxel = 0.0f;
  int kn = 10, ki = 10, kd = 5;
  int threads = 0;
  bool adaptive_k = false;
  float max_distance = 2.0f;
  float max_disagreement = DistanceConfig{}.max_disagreement_voxels;
  float max_extrapolation = DistanceConfig{}.max_extrapolation_voxels;
  std::size_t min_component = 20;
  float filter_voxel = 0.0f;
  int outlier_k = 0;
  float min_range = 0.0f, max_range = 0.0f;
  int depth_median = 0;          ///< depth frames: median window (3 or 5; 0 = off)
  float depth_bilateral = 0.0f;  ///< depth frames: bilateral depth sigma, metres (0 = off)
  std::string extract = "auto";
  std::string optimize = "default";
  std::size_t max_hole = 30;
  float decimate_to = 0.25f;
  float contour_tolerance = -1.0f;  ///< metres; negative: 0.4 voxel
  float max_projection = 0.0f;
  float plane_tolerance = ReconstructionConfig{}.plane_tolerance_voxels;
  float max_rim = ReconstructionConfig{}.max_rim_voxels;
  float remesh_tolerance = 0.0f;
  bool organized_as_depth = false;
  std::string normals = "auto";  ///< auto | input | estimate
  std::string orient = "auto";   ///< auto | sensor | propagate | input | viewpoint=X,Y,Z | ...
  std::string max_memory;        ///< --max-memory as given; empty: default_memory_limit()

  /// The stages' configuration; throws CLI::ValidationError for a malformed --orient.
  ReconstructionConfig config() const;
};

/// Registers --voxel --kn --ki --kd --threads --adaptive-k --max-distance --max-disagreement
/// --max-extrapolation --max-rim --min-component
/// --filter-voxel --outlier-k --min-range --max-range --depth-median --depth-bilateral
/// --extract --optimize --max-hole
/// --contour-tolerance --max-projection --plane-tolerance --remesh-tolerance --decimate-to
/// --organized-as-depth
/// --normals --orient on `cmd`, writing into `options`.
void add_pipeline_options(CLI::App* cmd, PipelineOptions& options);

/// Parses --orient: "auto", "sensor", "propagate", "input", "viewpoint=X,Y,Z" (towards a
/// point, metres) or "away=X,Y,Z" (away from a point, e.g. a closed object's centre) into
/// `normals`. Throws CLI::ValidationError naming what was expected.
void parse_orientation(const std::string& text, NormalsConfig& normals);

/// parse_orientation()'s message for `text` it refuses, without the option's name.
std::string orientation_expected(const std::string& text);

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
