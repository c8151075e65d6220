#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "graph/pipeline.h"
#include "nodes/filter/organized_depth.h"
#include "nodes/io/mesh_writers.h"
#include "nodes/io/parse_util.h"
#include "nodes/io/read_point_cloud.h"
#include "nodes/io/textured_obj.h"
#include "runtime/error.h"
#include "runtime/half_edge_mesh.h"
#include "runtime/threads.h"
#include "tools/commands.h"
#include "tools/pipeline_options.h"
#include "tools/report.h"

namespace meshflow::cli {

namespace {

struct ReconstructOptions {
  std::string input;
  std::string output;
  PipelineOptions pipeline;
  bool quiet = false;
  bool texture = false;
};

// Textures the planar regions of the frame's mesh from its coloured points and writes OBJ +
// MTL + PNG; returns the number of textures.
std::size_t write_textured(const std::string& output, const Frame& frame,
                           const ReconstructionConfig& config) {
  const PlanarSegmentation regions =
      grow_planar_regions(HalfEdgeMesh(frame.mesh), config.optimize.planes);
  const TexturedMesh textured = texture_planar_regions(frame.mesh, regions, frame.cloud);
  io::write_textured_obj(output, textured);
  return textured.textures.size();
}

// What `reconstruct` does for normals with the defaults (--normals auto --orient auto).
void print_normals_plan(const PointCloud& cloud) {
  if (cloud.has_normals()) {
    std::size_t missing = 0;
    for (const Eigen::Vector3f& n : cloud.normals)
      missing += n.allFinite() && n.squaredNorm() > 1e-12f ? 0 : 1;
    if (missing == 0)
      std::printf("normals     from the file, used as they are (--normals auto)\n");
    else
      std::printf("normals     from the file; %zu zero or NaN, estimated from their neighbours\n",
                  missing);
    return;
  }
  const NormalOrientation o = resolve_orientation(cloud);
  std::printf(
      "normals     none in the file: estimated, --orient auto = %s (%s)\n", orientation_name(o),
      o == NormalOrientation::kPropagate ? "no sensor position: consistent over neighbours, outward"
      : cloud.has_sensor_origin          ? "towards the sensor position"
                                         : "organized: towards the sensor at the origin");
}

void run_reconstruct(const ReconstructOptions& o) {
  ThreadLimit limit(o.pipeline.threads);
  const ReconstructionConfig config = o.pipeline.config();
  // Fail on an unwritable output before spending time on reconstruction.
  const std::string ext = io::lower_extension(o.output);
  if (ext != ".ply" && ext != ".obj") {
    throw Error(o.output, "", "unknown mesh format '" + ext + "' (expected .ply or .obj)");
  }
  if (o.texture && ext != ".obj")
    throw Error(o.output, "", "--texture writes OBJ + MTL + PNG: give an .obj output");

  ReconstructionPipeline pipeline(config, 1);
  auto frame = std::make_shared<Frame>();
  frame->name = o.input;
  const std::string path = o.input;
  frame->load = [path] { return io::read_point_cloud(path); };
  const double t0 = monotonic_seconds();
  bool given = false;
  pipeline.run([&]() -> FramePtr { return given ? nullptr : (given = true, frame); },
               [](const FramePtr&) {});
  throw_if_failed(*frame);
  if (frame->mesh.empty()) {
    throw Error(o.input, "",
                "no surface was extracted (voxel size " + std::to_string(frame->voxel_size) +
                    " m too small or too large?)");
  }
  if (o.texture && !frame->cloud.has_colors())
    throw Error(o.input, "", "--texture needs coloured points (the input has no colours)");
  std::size_t textures = 0;
  if (o.texture)
    textures = write_textured(o.output, *frame, config);
  else
    io::write_mesh(o.output, frame->mesh);
  const double wall = monotonic_seconds() - t0;
  if (frame->filter_counts.non_finite > 0) {
    std::fprintf(stderr, "meshflow: note: %s: dropped %zu non-finite (NaN/Inf) points\n",
                 o.input.c_str(), frame->filter_counts.non_finite);
  }
  if (!o.quiet) {
    print_frame_report(*frame, wall, limit.threads());
    if (o.texture) std::printf("textures   %zu planar regions textured\n", textures);
    std::printf("output     %s\n", o.output.c_str());
  }
}

}  // namespace

void add_reconstruct_command(CLI::App& app) {
  auto opts = std::make_shared<ReconstructOptions>();
  CLI::App* cmd = app.add_subcommand("reconstruct", "Reconstruct a mesh from one point cloud");
  cmd->add_option("input", opts->input, "Point cloud: .ply .pcd .xyz .txt .pts .asc .3d")
      ->required();
  cmd->add_option("-o,--output", opts->output, "Output mesh (.ply or .obj)")->required();
  add_pipeline_options(cmd, opts->pipeline);
  cmd->add_flag("-q,--quiet", opts->quiet, "Print nothing on success");
  cmd->add_flag("--texture", opts->texture,
                "Texture planar regions from the points' colours (OBJ + MTL + PNG output)");
  cmd->callback([opts] { run_reconstruct(*opts); });
}

void add_info_command(CLI::App& app) {
  auto path = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand("info", "Print counts, bounds and fields of a point cloud");
  cmd->add_option("file", *path, "Point cloud file")->required();
  cmd->callback([path] {
    const PointCloud cloud = io::read_point_cloud(*path);
    const std::size_t finite = count_finite_points(cloud);
    std::printf("file        %s\n", path->c_str());
    std::printf("points      %zu (%zu finite, %zu NaN/Inf)\n", cloud.size(), finite,
                cloud.size() - finite);
    if (cloud.is_organized()) {
      std::printf("organized   %u x %u", cloud.width, cloud.height);
      if (const std::optional<DepthFrame> depth = depth_frame_from_organized(cloud)) {
        const PinholeIntrinsics& k = depth->intrinsics;
        std::printf(
            ", a pinhole view: fx %.3f fy %.3f cx %.3f cy %.3f px (fuses as a depth "
            "image; --organized-as-depth)\n",
            k.fx, k.fy, k.cx, k.cy);
      } else {
        std::printf(", not a pinhole view from the sensor origin\n");
      }
    }
    std::string fields = "x y z";
    if (cloud.has_normals()) fields += " normals";
    if (cloud.has_colors()) fields += " rgb";
    if (cloud.has_intensities()) fields += " intensity";
    std::printf("fields      %s\n", fields.c_str());
    const Eigen::AlignedBox3f box = finite_bounds(cloud);
    if (!box.isEmpty()) {
      std::printf("bounds min  %.4f %.4f %.4f m\n", box.min().x(), box.min().y(), box.min().z());
      std::printf("bounds max  %.4f %.4f %.4f m\n", box.max().x(), box.max().y(), box.max().z());
      std::printf("extent      %.4f x %.4f x %.4f m\n", box.sizes().x(), box.sizes().y(),
                  box.sizes().z());
    }
    if (cloud.has_sensor_origin) {
      std::printf("sensor      %.4f %.4f %.4f m\n", cloud.sensor_origin.x(),
                  cloud.sensor_origin.y(), cloud.sensor_origin.z());
    }
    print_normals_plan(cloud);
  });
}

}  // namespace meshflow::cli
