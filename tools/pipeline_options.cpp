#include "tools/pipeline_options.h"

#include <cstdio>

#include "nodes/extract/extract_surface.h"
#include "nodes/synthetic/depth_sequence.h"
#include "nodes/synthetic/scan_sequence.h"
#include "tools/cli_checks.h"

namespace meshflow::cli {

ReconstructionConfig PipelineOptions::config() const {
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
  c.filter.min_range = min_range;
  c.filter.max_range = max_range;
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
  c.organized_as_depth = organized_as_depth;
  c.normals.source = normals == "input"      ? NormalSource::kInput
                     : normals == "estimate" ? NormalSource::kEstimate
                                             : NormalSource::kAuto;
  parse_orientation(orient, c.normals);
  c.max_memory_bytes =
      max_memory.empty() ? default_memory_limit() : parse_byte_size(max_memory, "--max-memory");
  return c;
}

void parse_orientation(const std::string& text, NormalsConfig& normals) {
  static const std::pair<const char*, NormalOrientation> kNamed[] = {
      {"auto", NormalOrientation::kAuto},
      {"sensor", NormalOrientation::kTowardSensor},
      {"propagate", NormalOrientation::kPropagate},
      {"input", NormalOrientation::kInput}};
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
  throw CLI::ValidationError("--orient",
                             "expected auto, sensor, propagate, input, "
                             "viewpoint=X,Y,Z or away=X,Y,Z; got '" +
                                 text + "'");
}

void add_pipeline_options(CLI::App* cmd, PipelineOptions& o) {
  cmd->add_option("--voxel", o.voxel, "Voxel size in metres (default: 3x the median point spacing)")
      ->check(number_in(0, 1000));
  cmd->add_option("--kn", o.kn, "Neighbours for normal estimation")->check(CLI::Range(3, 1000));
  cmd->add_option("--ki", o.ki, "Neighbours for normal interpolation (0 = off)")
      ->check(CLI::Range(0, 1000));
  cmd->add_option("--kd", o.kd, "Tangent planes averaged per distance sample")
      ->check(CLI::Range(1, 64));
  cmd->add_option("--threads", o.threads, "Worker threads (default: all cores)")
      ->check(CLI::Range(0, 1024));
  cmd->add_option("--max-memory", o.max_memory,
                  "Refuse a frame whose points, grid and distances (or a fused map) would take "
                  "more memory: 512M, 4G, ...; 0 = no limit (default: 80 % of physical memory)")
      ->check(byte_size());
  cmd->add_flag("--adaptive-k", o.adaptive_k, "Grow kn where neighbourhoods are degenerate");
  cmd->add_option("--max-distance", o.max_distance,
                  "Distance samples farther than this many voxels from the data are invalid")
      ->check(number_in(0, 1000, true));
  cmd->add_option("--max-disagreement", o.max_disagreement,
                  "Distance samples that one tangent plane puts this many voxels outside and "
                  "another as far inside are invalid (phantom sheets; 0 = off)")
      ->check(number_in(0, 1000));
  cmd->add_option("--max-extrapolation", o.max_extrapolation,
                  "Distance samples whose foot lies this many voxels beyond their nearest "
                  "points' extent are invalid (surface past a scan's border; 0 = off)")
      ->check(number_in(0, 1000));
  cmd->add_option("--max-rim", o.max_rim,
                  "Border triangles farther than this many voxels from the data are peeled off "
                  "(an open scan's rim; 0 = off)")
      ->check(number_in(0, 1000));
  cmd->add_option("--min-component", o.min_component,
                  "Remove mesh components with fewer triangles (the clean step and per-frame "
                  "triangulation; 0 = keep all)")
      ->check(number_in(0, 1e9));
  cmd->add_option("--filter-voxel", o.filter_voxel,
                  "Voxel-grid downsampling before meshing, metres (0 = off)")
      ->check(number_in(0, 1000));
  cmd->add_option("--outlier-k", o.outlier_k,
                  "Statistical outlier removal with k neighbours (0 = off)")
      ->check(CLI::Range(0, 1000));
  cmd->add_option("--min-range", o.min_range, "Drop points closer to the sensor, metres")
      ->check(number_in(0, 1e6));
  cmd->add_option("--extract", o.extract,
                  "Extraction: auto (emc for clean samples without a sensor, else mc), mc "
                  "(marching cubes), mt (marching tetrahedra), emc (extended MC, sharp features), "
                  "pmc (planar MC)")
      ->check(CLI::IsMember({"auto", "mc", "mt", "emc", "pmc"}));
  cmd->add_option("--max-range", o.max_range,
                  "Drop points farther from the sensor, metres (0 = off)")
      ->check(number_in(0, 1e6));
  cmd->add_option("--depth-median", o.depth_median,
                  "Depth frames: median of each pixel's 3 x 3 or 5 x 5 window of valid depths "
                  "before meshing or fusion (0 = off); drops no pixel")
      ->check(CLI::IsMember({0, 3, 5}));
  cmd->add_option("--depth-bilateral", o.depth_bilateral,
                  "Depth frames: bilateral smoothing with this depth sigma, metres (e.g. 0.01; "
                  "0 = off); drops no pixel")
      ->check(number_in(0, 10));
  cmd->add_option("--optimize", o.optimize,
                  "Mesh optimisation: default (clean,holes), none, or a list of clean, holes, "
                  "planes, sharpen, retriangulate, remesh, decimate in the order to run")
      ->check([](const std::string& list) -> std::string {
        try {
          parse_optimize_steps(list);
          return "";
        } catch (const std::exception& e) {
          return e.what();
        }
      });
  cmd->add_option("--max-hole", o.max_hole, "holes step: close border loops up to this many edges")
      ->check(number_in(0, 1e9));
  cmd->add_option("--contour-tolerance", o.contour_tolerance,
                  "retriangulate step: Douglas-Peucker tolerance of region contours, metres "
                  "(default: 0.4 voxel)")
      ->check(number_in(0, 1000));
  cmd->add_option("--max-projection", o.max_projection,
                  "planes step: vertices farther from their plane stay, metres (0 = no limit)")
      ->check(number_in(0, 1000));
  cmd->add_option("--plane-tolerance", o.plane_tolerance,
                  "planes/sharpen/retriangulate: a region is planar only when 95 % of its "
                  "vertices lie within this many voxels of its plane (0 = no check)")
      ->check(number_in(0, 1000));
  cmd->add_option("--remesh-tolerance", o.remesh_tolerance,
                  "remesh step: largest deviation of an edge from the surface, metres "
                  "(0 = a quarter of the median edge)")
      ->check(number_in(0, 1000));
  cmd->add_option("--decimate-to", o.decimate_to, "decimate step: share of the triangles to keep")
      ->check(number_in(0, 1));
  cmd->add_option("--normals", o.normals,
                  "Point normals: auto (the input's when it has them, else estimated), input, "
                  "estimate")
      ->check(CLI::IsMember({"auto", "input", "estimate"}));
  cmd->add_option("--orient", o.orient,
                  "Orientation of estimated normals: auto (the input normals' signs, else the "
                  "sensor where the data has one, else propagate), sensor, propagate "
                  "(consistent over neighbours, for objects without a sensor), input, "
                  "viewpoint=X,Y,Z, away=X,Y,Z")
      ->check([](const std::string& text) -> std::string {
        try {
          NormalsConfig probe;
          parse_orientation(text, probe);
          return "";
        } catch (const CLI::ValidationError& e) {
          return e.what();
        }
      });
  cmd->add_flag("--organized-as-depth", o.organized_as_depth,
                "Organized clouds that are a pinhole back-projection (Kinect PCDs): take the "
                "depth-image path (image normals, projective distance; faster, single view)");
}

void TriangulationOptions::apply(ReconstructionConfig& config) const {
  config.triangulation.method = method == "rqt" ? DepthTriangulationMethod::kRestrictedQuadtree
                                                : DepthTriangulationMethod::kNaive;
  config.triangulation.quadtree.error_per_depth2 = rqt_error;
  config.triangulation.quadtree.noise_multiple = rqt_noise_multiple;
  config.triangulation.decimate_to = decimate;
}

void add_triangulation_options(CLI::App* cmd, TriangulationOptions& o) {
  cmd->add_option("--triangulate", o.method,
                  "Triangulate each depth map or organized point cloud (naive or rqt) instead of "
                  "the volumetric stages")
      ->check(CLI::IsMember({"naive", "rqt"}));
  cmd->add_option("--rqt-error", o.rqt_error,
                  "rqt: allowed deviation per squared depth, 1/m (error <= k depth^2)")
      ->check(number_in(0, 1e6, true));
  cmd->add_option("--rqt-noise-multiple", o.rqt_noise_multiple,
                  "rqt: raise that allowance to this many times each frame's estimated depth "
                  "noise per squared depth (0 = off)")
      ->check(number_in(0, 100));
  cmd->add_option("--decimate", o.decimate,
                  "With --triangulate: QEM-decimate each frame's mesh to this share (e.g. 0.25)")
      ->check(number_in(0, 1));
}

void add_sequence_options(CLI::App* cmd, SequenceArgument& a) {
  cmd->add_option("sequence", a.path,
                  "A directory of 3DTK scans (scanNNN.3d + .pose), of point cloud files (.pcd, "
                  ".ply) or of depth images (Redwood, TUM or bare *depth* images), or one point "
                  "cloud file");
  auto* scans =
      cmd->add_flag("--synthetic", a.synthetic, "Use the built-in synthetic laser-scan sequence");
  cmd->add_flag("--synthetic-depth", a.synthetic_depth,
                "Use the built-in synthetic depth-camera sequence (640x480)")
      ->excludes(scans);
  cmd->add_option("--synthetic-frames", a.synthetic_frames,
                  "Frames of the built-in sequence (a full turn of the camera or scanner)")
      ->check(CLI::Range(1, 1000000));
  cmd->add_option("--synthetic-size", a.synthetic_size,
                  "Image size of the built-in depth camera, WxH (default 640x480; the focal "
                  "length scales with the width)")
      ->check([](const std::string& text) -> std::string {
        int w = 0, h = 0;
        char end = 0;
        return std::sscanf(text.c_str(), "%dx%d%c", &w, &h, &end) == 2 && w >= 16 && h >= 16 &&
                       w <= 8192 && h <= 8192
                   ? ""
                   : "expected WxH between 16x16 and 8192x8192, got '" + text + "'";
      });
  cmd->add_option("--in-flight", a.in_flight, "Frames in the pipeline at once")
      ->check(CLI::Range(1, 64));
  cmd->add_option("--every", a.every, "Take every N-th frame")->check(CLI::Range(1, 1000000));
  cmd->add_option("--max-frames", a.max_frames, "Stop after N frames (0 = all)")
      ->check(number_in(0, 1e15));
}

std::unique_ptr<io::Sequence> open_sequence_argument(const SequenceArgument& a) {
  if (a.synthetic) {
    synthetic::ScanSequenceConfig c;
    c.frames = a.synthetic_frames;
    return synthetic::make_scan_sequence(synthetic::demo_room_scene(), c);
  }
  if (a.synthetic_depth) {
    synthetic::DepthSequenceConfig c;
    c.frames = a.synthetic_frames;
    int width = 0, height = 0;
    if (std::sscanf(a.synthetic_size.c_str(), "%dx%d", &width, &height) == 2)
      c.intrinsics = synthetic::scaled_default_camera(width, height);
    return synthetic::make_depth_sequence(synthetic::demo_room_scene(), c);
  }
  if (a.path.empty())
    throw CLI::ValidationError("sequence",
                               "give a SEQUENCE path, --synthetic or --synthetic-depth");
  return io::open_sequence(a.path);
}

}  // namespace meshflow::cli
