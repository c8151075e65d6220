#pragma once
// The option model: every setting the front ends (the `meshflow` CLI, the Python module) give
// the reconstruction stages, in one table with its name, help, default and check. Front ends
// are adapters: the CLI registers each entry as --name, Python as a keyword (dashes become
// underscores); both validate values here, so the same value is refused the same way with the
// same message everywhere. Adding a knob: a field of PipelineOptions, a row of the table and its
// line in PipelineOptions::config(). No front-end type (CLI11, pybind11) appears here.

#include <cstddef>
#include <functional>
#include <string>
#include <variant>
#include <vector>

#include "graph/reconstruction_config.h"

namespace meshflow::options {

/// The settings, as a user gives them (sentinels where "automatic" has no number).
struct PipelineOptions {
  float voxel = 0.0f;  ///< metres; 0: 3x the median point spacing
  int kn = 10, ki = 10, kd = 5;
  int threads = 0;  ///< 0: all cores
  bool adaptive_k = false;
  float max_distance = 2.0f;
  float max_disagreement = DistanceConfig{}.max_disagreement_voxels;
  float max_extrapolation = DistanceConfig{}.max_extrapolation_voxels;
  std::size_t min_component = 20;
  float filter_voxel = 0.0f;
  int outlier_k = 0;
  std::size_t outlier_cluster = FilterConfig{}.outlier_cluster;
  float outlier_radius = FilterConfig{}.outlier_radius_voxels;
  float min_range = 0.0f, max_range = 0.0f;
  std::string crop;      ///< "minx,miny,minz,maxx,maxy,maxz" metres (parse_crop_box); empty: none
  int depth_median = 0;  ///< depth frames: median window (3 or 5; 0 = off)
  float depth_bilateral = 0.0f;  ///< depth frames: bilateral depth sigma, metres (0 = off)
  std::string extract = "auto";
  std::string optimize = "default";
  std::size_t max_hole = 30;
  float decimate_to = 0.25f;
  float contour_tolerance = -1.0f;  ///< metres; -1: 0.4 voxel
  float max_projection = 0.0f;
  float plane_tolerance = ReconstructionConfig{}.plane_tolerance_voxels;
  float max_rim = ReconstructionConfig{}.max_rim_voxels;
  float remesh_tolerance = 0.0f;
  float feature_angle = kDefaultFeatureAngleDeg;  ///< degrees; 180: no sharp edges kept
  bool organized_as_depth = false;
  bool close = false;  ///< --close: a watertight surface (volumetric diffusion of the distance)
  std::string normals = "auto";  ///< auto | input | estimate
  std::string orient = "auto";   ///< see parse_orientation()
  std::string max_memory;        ///< "512M", "4G", "0"; empty: default_memory_limit()
  /// Compressed meshes (--compress): octahedral bits per normal coordinate, 0 = recomputed.
  int normal_bits = static_cast<int>(compress::kDefaultNormalBits);
  /// Compressed meshes: the largest angle, degrees, between an input normal and its decoded
  /// one, in place of normal_bits' bound; 0: from normal_bits.
  float normal_error = 0.0f;

  /// The stages' configuration. Throws meshflow::Error (source "--NAME") for the first option
  /// that fails its check (validate()). O(options).
  ReconstructionConfig config() const;
};

/// A field of PipelineOptions, by type.
using OptionField =
    std::variant<float PipelineOptions::*, int PipelineOptions::*, std::size_t PipelineOptions::*,
                 bool PipelineOptions::*, std::string PipelineOptions::*>;

/// One row of the model.
struct OptionSpec {
  const char* name;  ///< as the CLI spells it without "--": "max-distance"
  OptionField field;
  const char* help;
  /// What the default means where the stored default is a sentinel ("3x the median point
  /// spacing"); nullptr: the stored value says it.
  const char* default_text;
  /// Checks the field's value in `options`: "" when valid, else what was expected and what was
  /// given ("expected a number in [0, 1000], got -5"), without the option's name.
  std::function<std::string(const PipelineOptions& options)> check;
};

/// The table, in the order the CLI's help lists them. Thread-safe (a constant).
const std::vector<OptionSpec>& pipeline_option_specs();

/// The row named `name` (CLI spelling without "--"). Throws std::out_of_range for a name not in
/// the table (a programming error). O(rows).
const OptionSpec& option_spec(const std::string& name);

/// `spec`'s name as a Python keyword: dashes as underscores; "normals" is "normal_source" there
/// (Python's `normals` argument is the normal array).
std::string python_name(const OptionSpec& spec);

/// Throws meshflow::Error("--NAME", "", problem) for the first option of `options` that fails
/// its check. O(options).
void validate(const PipelineOptions& options);

/// Parses an orientation: "auto", "sensor", "propagate", "input", "up", "down", "flip" (auto,
/// turned over), "viewpoint=X,Y,Z" (towards a point, metres, the file's own coordinates) or
/// "away=X,Y,Z" (away from a point, e.g. a closed object's centre) into `normals`. Throws
/// meshflow::Error("--orient", "", what was expected).
void parse_orientation(const std::string& text, NormalsConfig& normals);

/// Parses a crop box "minx,miny,minz,maxx,maxy,maxz" (metres, the file's own coordinates: six
/// finite numbers, each min below its max) into `filter`'s crop_min / crop_max. Throws
/// meshflow::Error("--crop", "", what was expected and what was given). O(1).
void parse_crop_box(const std::string& text, FilterConfig& filter);

/// Bytes from a size as users write it: a number with an optional K, M, G or T suffix (powers of
/// 1024, e.g. "512M", "1.5G"; no suffix = bytes), "0" for no limit. Throws
/// meshflow::Error(option, "", what was expected) for anything else.
std::size_t parse_byte_size(const std::string& text, const std::string& option);

/// The --max-memory default: 80 % of the machine's physical memory (0 when it cannot be read).
std::size_t default_memory_limit();

/// "" when `value` is finite and in [low, high] ((low, high] when `low_open`), else "expected a
/// number in [low, high], got VALUE" (also the CLI's message for text that is no number).
std::string check_number(double value, double low, double high, bool low_open = false);

}  // namespace meshflow::options
