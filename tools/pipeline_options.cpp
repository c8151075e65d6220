#include "tools/pipeline_options.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <type_traits>

#include "nodes/extract/extract_surface.h"
#include "nodes/synthetic/depth_sequence.h"
#include "nodes/synthetic/scan_sequence.h"
#include "runtime/error.h"
#include "tools/cli_checks.h"
#include "tools/model_check.h"

namespace meshflow::cli {

void add_pipeline_options(CLI::App* cmd, PipelineOptions& o) {
  for (const options::OptionSpec& spec : options::pipeline_option_specs()) {
    const std::string flag = std::string("--") + spec.name;
    std::visit(
        [&](auto member) {
          using T = std::remove_reference_t<decltype(o.*member)>;
          if constexpr (std::is_same_v<T, bool>) {
            cmd->add_flag(flag, o.*member, spec.help);
          } else {
            CLI::Option* option = cmd->add_option(flag, o.*member, spec.help)
                                      ->check(model_check<PipelineOptions>(spec, member));
            if (spec.default_text != nullptr) option->default_str(spec.default_text);
          }
        },
        spec.field);
  }
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
      })
      ->default_str("640x480");
  cmd->add_option("--in-flight", a.in_flight, "Frames in the pipeline at once")
      ->check(CLI::Range(1, 64));
  cmd->add_option("--every", a.every, "Take every N-th frame")->check(CLI::Range(1, 1000000));
  cmd->add_option("--max-frames", a.max_frames, "Stop after N frames (0 = all)")
      ->check(number_in(0, 1e15))
      ->default_str("all");
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
