#include "options/pipeline_options.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "nodes/extract/extract_surface.h"
#include "nodes/optimize/optimize_mesh.h"
#include "runtime/error.h"

namespace meshflow::options {
namespace {

using O = PipelineOptions;

// "12", "0.25", "1e+06": a value as a user would type it.
std::string number_text(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

// A check that the numeric field `member` lies in [low, high] ((low, high] when low_open).
template <typename T>
std::function<std::string(const O&)> in_range(T O::*member, double low, double high,
                                              bool low_open = false) {
  return
      [=](const O& o) { return check_number(static_cast<double>(o.*member), low, high, low_open); };
}

// Like in_range(), but the sentinel `automatic` (the default meaning "work it out") passes too.
std::function<std::string(const O&)> in_range_or(float O::*member, float automatic, double low,
                                                 double high) {
  return [=](const O& o) {
    return o.*member == automatic ? std::string() : check_number(o.*member, low, high);
  };
}

// A check that the text or integer field is one of `choices`.
template <typename T>
std::function<std::string(const O&)> one_of(T O::*member, std::vector<T> choices) {
  return [=](const O& o) -> std::string {
    if (std::find(choices.begin(), choices.end(), o.*member) != choices.end()) return "";
    std::string expected = "expected one of";
    const char* separator = " ";
    std::string given;
    for (const T& c : choices) {
      if constexpr (std::is_same_v<T, std::string>)
        expected += separator + c;
      else
        expected += separator + std::to_string(c);
      separator = ", ";
    }
    if constexpr (std::is_same_v<T, std::string>)
      given = "'" + o.*member + "'";
    else
      given = std::to_string(o.*member);
    return expected + "; got " + given;
  };
}

// A check by a parser that throws meshflow::Error (its problem is the message).
template <typename Parse>
std::function<std::string(const O&)> parses(std::string O::*member, Parse parse) {
  return [=](const O& o) -> std::string {
    try {
      parse(o.*member);
      return "";
    } catch (const Error& e) {  // its source is the option; the location stays ("step 'foo'")
      return e.location().empty() ? e.problem() : e.location() + ": " + e.problem();
    }
  };
}

std::function<std::string(const O&)> always_valid() {
  return [](const O&) { return std::string(); };
}

std::vector<OptionSpec> make_specs() {
  return {
      {"voxel", &O::voxel, "Voxel size in metres (auto: 3x the median point spacing)", "auto",
       in_range(&O::voxel, 0, 1000)},
      {"kn", &O::kn, "Neighbours for normal estimation", nullptr, in_range(&O::kn, 3, 1000)},
      {"ki", &O::ki, "Neighbours for normal interpolation (0 = off)", nullptr,
       in_range(&O::ki, 0, 1000)},
      {"kd", &O::kd, "Tangent planes averaged per distance sample", nullptr,
       in_range(&O::kd, 1, 64)},
      {"threads", &O::threads, "Worker threads (0: all cores)", "all cores",
       in_range(&O::threads, 0, 1024)},
      {"max-memory", &O::max_memory,
       "Refuse a frame whose points, grid and distances (or a fused map) would take more memory: "
       "512M, 4G, ...; 0 = no limit",
       "80% of RAM",
       [](const O& o) -> std::string {
         if (o.max_memory.empty()) return "";
         try {
           parse_byte_size(o.max_memory, "--max-memory");
           return "";
         } catch (const Error& e) {
           return e.problem();
         }
       }},
      {"adaptive-k", &O::adaptive_k, "Grow kn where neighbourhoods are degenerate", nullptr,
       always_valid()},
      {"max-distance", &O::max_distance,
       "Distance samples farther than this many voxels from the data are invalid", nullptr,
       in_range(&O::max_distance, 0, 1000, true)},
      {"max-disagreement", &O::max_disagreement,
       "Distance samples that one tangent plane puts this many voxels outside and another as far "
       "inside are invalid (phantom sheets; 0 = off)",
       nullptr, in_range(&O::max_disagreement, 0, 1000)},
      {"max-extrapolation", &O::max_extrapolation,
       "Distance samples whose foot lies this many voxels beyond their nearest points' extent are "
       "invalid (surface past a scan's border; 0 = off)",
       nullptr, in_range(&O::max_extrapolation, 0, 1000)},
      {"max-rim", &O::max_rim,
       "Border triangles farther than this many voxels from the data are peeled off (an open "
       "scan's rim; 0 = off)",
       nullptr, in_range(&O::max_rim, 0, 1000)},
      {"min-component", &O::min_component,
       "Remove mesh components with fewer triangles (the clean step and per-frame "
       "triangulation; 0 = keep all)",
       nullptr, in_range(&O::min_component, 0, 1e9)},
      {"filter-voxel", &O::filter_voxel, "Voxel-grid downsampling before meshing, metres (0 = off)",
       nullptr, in_range(&O::filter_voxel, 0, 1000)},
      {"outlier-k", &O::outlier_k, "Statistical outlier removal with k neighbours (0 = off)",
       nullptr, in_range(&O::outlier_k, 0, 1000)},
      {"outlier-cluster", &O::outlier_cluster,
       "Drop points whose cluster (points linked to neighbours within --outlier-radius voxels) "
       "has fewer points: isolated points and sparse clusters that cannot make a surface (0 = "
       "off)",
       nullptr, in_range(&O::outlier_cluster, 0, 1e9)},
      {"outlier-radius", &O::outlier_radius,
       "Longest link between points of one cluster for --outlier-cluster, voxels", nullptr,
       in_range(&O::outlier_radius, 0, 1000, true)},
      {"min-range", &O::min_range, "Drop points closer to the sensor, metres", nullptr,
       in_range(&O::min_range, 0, 1e6)},
      {"crop", &O::crop,
       "Keep only the points inside the box minx,miny,minz,maxx,maxy,maxz (metres, the file's "
       "own coordinates), right after reading",
       "none",
       parses(&O::crop,
              [](const std::string& s) {
                FilterConfig probe;
                parse_crop_box(s, probe);
              })},
      {"max-range", &O::max_range, "Drop points farther from the sensor, metres (0 = off)", nullptr,
       in_range(&O::max_range, 0, 1e6)},
      {"extract", &O::extract,
       "Extraction: auto (emc for clean samples without a sensor, else mc), mc (marching cubes), "
       "mt (marching tetrahedra), emc (extended MC, sharp features), pmc (planar MC)",
       nullptr, one_of<std::string>(&O::extract, {"auto", "mc", "mt", "emc", "pmc"})},
      {"depth-median", &O::depth_median,
       "Depth frames: median of each pixel's 3 x 3 or 5 x 5 window of valid depths before "
       "meshing or fusion (0 = off); drops no pixel",
       nullptr, one_of<int>(&O::depth_median, {0, 3, 5})},
      {"depth-bilateral", &O::depth_bilateral,
       "Depth frames: bilateral smoothing with this depth sigma, metres (e.g. 0.01; 0 = off); "
       "drops no pixel",
       nullptr, in_range(&O::depth_bilateral, 0, 10)},
      {"optimize", &O::optimize,
       "Mesh optimisation: default (clean,holes), none, or a list of clean, holes, planes, "
       "sharpen, retriangulate, remesh, decimate in the order to run",
       nullptr, parses(&O::optimize, [](const std::string& s) { parse_optimize_steps(s); })},
      {"max-hole", &O::max_hole, "holes step: close border loops up to this many edges", nullptr,
       in_range(&O::max_hole, 0, 1e9)},
      {"contour-tolerance", &O::contour_tolerance,
       "retriangulate step: Douglas-Peucker tolerance of region contours, metres (auto: 0.4 "
       "voxel)",
       "auto", in_range_or(&O::contour_tolerance, -1.0f, 0, 1000)},
      {"max-projection", &O::max_projection,
       "planes step: vertices farther from their plane stay, metres (0 = no limit)", nullptr,
       in_range(&O::max_projection, 0, 1000)},
      {"plane-tolerance", &O::plane_tolerance,
       "planes/sharpen/retriangulate: a region is planar only when 95 % of its vertices lie "
       "within this many voxels of its plane (0 = no check)",
       nullptr, in_range(&O::plane_tolerance, 0, 1000)},
      {"remesh-tolerance", &O::remesh_tolerance,
       "remesh step: largest deviation of an edge from the surface, metres (auto, 0: six times "
       "the mesh's roughness, within 0.01-0.25 of the median edge)",
       "auto", in_range(&O::remesh_tolerance, 0, 1000)},
      {"feature-angle", &O::feature_angle,
       "Reducing optimize steps: edges whose faces meet at more than this many degrees are "
       "sharp and kept (corners fixed, feature vertices moved only along their line); 180 = "
       "none",
       nullptr, in_range(&O::feature_angle, 0, 180)},
      {"decimate-to", &O::decimate_to, "decimate step: share of the triangles to keep", nullptr,
       in_range(&O::decimate_to, 0, 1)},
      {"normals", &O::normals,
       "Point normals: auto (the input's when it has them, else estimated), input, estimate",
       nullptr, one_of<std::string>(&O::normals, {"auto", "input", "estimate"})},
      {"normal-bits", &O::normal_bits,
       "Compressed meshes (.mfc): normal precision in bits, 4..20 (10: within 0.25 degrees, "
       "doubling per bit fewer; Draco's default grid is within 0.26); 0 stores no normals and the "
       "decoder recomputes them from "
       "the decoded geometry",
       nullptr,
       [](const O& o) -> std::string {
         if (o.normal_bits == 0 || (o.normal_bits >= static_cast<int>(compress::kMinNormalBits) &&
                                    o.normal_bits <= static_cast<int>(compress::kMaxNormalBits)))
           return "";
         return "expected 0 or an integer in [4, 20], got " + std::to_string(o.normal_bits);
       }},
      {"normal-error", &O::normal_error,
       "Compressed meshes (.mfc): the largest angle, degrees, between an input normal and its "
       "decoded normal, 0.001..30, in place of --normal-bits' bound (0.25 at 10 bits, doubling "
       "per bit fewer)",
       "from --normal-bits", in_range_or(&O::normal_error, 0.0f, 0.001, 30.0)},
      {"orient", &O::orient,
       "Orientation of estimated normals: auto (the input normals' signs, else the sensor where "
       "the data has one, else propagate), sensor, propagate (consistent over neighbours, then up "
       "for LAS, towards the origin for one camera view in its camera frame, else outward), "
       "input, up, down (propagate, facing +z / -z), flip (auto turned over), viewpoint=X,Y,Z, "
       "away=X,Y,Z (the file's own coordinates)",
       nullptr,
       parses(&O::orient,
              [](const std::string& s) {
                NormalsConfig probe;
                parse_orientation(s, probe);
              })},
      {"close", &O::close,
       "Watertight output: the distance where no data is (unseen parts, holes) filled by "
       "volumetric diffusion, data's distances kept, lines of sight kept empty when a sensor is "
       "known; one closed surface per object",
       nullptr, always_valid()},
      {"organized-as-depth", &O::organized_as_depth,
       "Organized clouds that are a pinhole back-projection (Kinect PCDs): take the depth-image "
       "path (image normals, projective distance; faster, single view)",
       nullptr, always_valid()},
  };
}

}  // namespace

const std::vector<OptionSpec>& pipeline_option_specs() {
  static const std::vector<OptionSpec> specs = make_specs();
  return specs;
}

const OptionSpec& option_spec(const std::string& name) {
  for (const OptionSpec& spec : pipeline_option_specs())
    if (name == spec.name) return spec;
  throw std::out_of_range("option_spec: '" + name + "' is not in the option model");
}

std::string python_name(const OptionSpec& spec) {
  std::string name = spec.name;
  if (name == "normals") return "normal_source";
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

void validate(const PipelineOptions& options) {
  for (const OptionSpec& spec : pipeline_option_specs()) {
    const std::string problem = spec.check(options);
    if (!problem.empty()) throw Error(std::string("--") + spec.name, "", problem);
  }
}

std::string check_number(double value, double low, double high, bool low_open) {
  const bool inside =
      std::isfinite(value) && (low_open ? value > low : value >= low) && value <= high;
  if (inside) return "";
  return "expected a number in " + std::string(low_open ? "(" : "[") + number_text(low) + ", " +
         number_text(high) + "], got " + number_text(value);
}

ReconstructionConfig PipelineOptions::config() const {
  validate(*this);
  ReconstructionConfig c;
  c.voxelize.voxel_size = voxel;
  c.normals.kn = kn;
  c.normals.ki = ki;
  c.normals.adaptive_k = adaptive_k;
  c.distance.kd = kd;
  c.distance.max_distance_voxels = max_distance;
  c.distance.max_disagreement_voxels = max_disagreement;
  c.distance.max_extrapolation_voxels = max_extrapolation;
  c.optimize.cleanup.min_component_triangles = min_component;
  c.triangulation.min_component_triangles = min_component;  // one setting for both paths
  c.filter.voxel_size = filter_voxel;
  c.filter.outlier_k = outlier_k;
  c.filter.outlier_cluster = outlier_cluster;
  c.filter.outlier_radius_voxels = outlier_radius;
  c.filter.min_range = min_range;
  c.filter.max_range = max_range;
  parse_crop_box(crop, c.filter);
  c.depth_filter.median_kernel = depth_median;
  c.depth_filter.bilateral_sigma_depth = depth_bilateral;
  c.extract.method = parse_extract_method(extract);
  c.optimize.steps = parse_optimize_steps(optimize);
  c.optimize.holes.max_edges = max_hole;
  c.optimize.decimate.target_ratio = decimate_to;
  if (contour_tolerance >= 0.0f) {  // given in metres
    c.optimize.retriangulation.contour_tolerance = contour_tolerance;
    c.contour_tolerance_voxels = 0.0f;
  }
  c.optimize.planes.max_projection = max_projection;
  c.plane_tolerance_voxels = plane_tolerance;
  c.max_rim_voxels = max_rim;
  c.optimize.remesh.tolerance = remesh_tolerance;
  c.optimize.feature_angle_deg = feature_angle;
  c.organized_as_depth = organized_as_depth;
  c.close.enabled = close;
  c.normals.source = normals == "input"      ? NormalSource::kInput
                     : normals == "estimate" ? NormalSource::kEstimate
                                             : NormalSource::kAuto;
  parse_orientation(orient, c.normals);
  c.compress.normal_bits = static_cast<unsigned>(normal_bits);
  c.compress.normal_error = static_cast<double>(normal_error);
  c.max_memory_bytes =
      max_memory.empty() ? default_memory_limit() : parse_byte_size(max_memory, "--max-memory");
  return c;
}

void parse_orientation(const std::string& text, NormalsConfig& normals) {
  static const std::pair<const char*, NormalOrientation> kNamed[] = {
      {"auto", NormalOrientation::kAuto},
      {"sensor", NormalOrientation::kTowardSensor},
      {"propagate", NormalOrientation::kPropagate},
      {"input", NormalOrientation::kInput},
      {"up", NormalOrientation::kUp},
      {"down", NormalOrientation::kDown}};
  if (text == "flip") {  // the automatic result, turned over
    normals.orientation = NormalOrientation::kAuto;
    normals.flip = true;
    return;
  }
  for (const auto& [name, orientation] : kNamed) {
    if (text == name) {
      normals.orientation = orientation;
      return;
    }
  }
  const std::size_t eq = text.find('=');
  const std::string kind = text.substr(0, eq);
  if (eq != std::string::npos && (kind == "viewpoint" || kind == "away")) {
    Eigen::Vector3f point;
    char tail = 0;
    if (std::sscanf(text.c_str() + eq + 1, "%f,%f,%f%c", &point.x(), &point.y(), &point.z(),
                    &tail) == 3 &&
        point.allFinite()) {
      normals.orientation = kind == "viewpoint" ? NormalOrientation::kTowardViewpoint
                                                : NormalOrientation::kAwayFromViewpoint;
      normals.viewpoint = point;
      return;
    }
  }
  throw Error("--orient", "",
              "expected auto, sensor, propagate, input, up, down, flip, viewpoint=X,Y,Z or "
              "away=X,Y,Z; got '" +
                  text + "'");
}

void parse_crop_box(const std::string& text, FilterConfig& filter) {
  if (text.empty()) return;  // no crop
  std::vector<float> values;
  std::size_t at = 0;
  bool numbers = true;
  while (numbers && at <= text.size()) {
    const std::size_t comma = std::min(text.find(',', at), text.size());
    const std::string item = text.substr(at, comma - at);
    char* end = nullptr;
    const double value = std::strtod(item.c_str(), &end);
    numbers = !item.empty() && end != item.c_str() && *end == '\0' && std::isfinite(value) &&
              std::abs(value) <= 1e9;
    values.push_back(static_cast<float>(value));
    at = comma + 1;
  }
  if (!numbers || values.size() != 6)
    throw Error("--crop", "",
                "expected six numbers minx,miny,minz,maxx,maxy,maxz (metres), got '" + text + "'");
  for (int k = 0; k < 3; ++k) {
    if (values[static_cast<std::size_t>(k)] >= values[static_cast<std::size_t>(k + 3)])
      throw Error("--crop", "",
                  std::string("min") + "xyz"[k] + " must be below max" + "xyz"[k] + ", got " +
                      number_text(values[static_cast<std::size_t>(k)]) + " and " +
                      number_text(values[static_cast<std::size_t>(k + 3)]) + " in '" + text + "'");
  }
  filter.crop_min = Eigen::Vector3f(values[0], values[1], values[2]);
  filter.crop_max = Eigen::Vector3f(values[3], values[4], values[5]);
}

std::size_t parse_byte_size(const std::string& text, const std::string& option) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  const std::string suffix(end == nullptr ? "" : end);
  double scale = 0.0;
  if (suffix.empty() || suffix == "B") scale = 1.0;
  if (suffix == "K" || suffix == "k") scale = 1024.0;
  if (suffix == "M" || suffix == "m") scale = 1024.0 * 1024.0;
  if (suffix == "G" || suffix == "g") scale = 1024.0 * 1024.0 * 1024.0;
  if (suffix == "T" || suffix == "t") scale = 1024.0 * 1024.0 * 1024.0 * 1024.0;
  const double bytes = value * scale;
  if (end == text.c_str() || scale == 0.0 || !std::isfinite(bytes) || bytes < 0.0 || bytes > 1e18)
    throw Error(option, "", "expected a size such as 512M, 4G or 0 (no limit), got '" + text + "'");
  return static_cast<std::size_t>(bytes);
}

std::size_t default_memory_limit() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  if (pages <= 0 || page <= 0) return 0;
  return static_cast<std::size_t>(pages) / 5 * 4 * static_cast<std::size_t>(page);
}

}  // namespace meshflow::options
