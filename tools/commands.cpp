#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "graph/pipeline.h"
#include "nodes/chunk/phase_times.h"
#include "nodes/compress/compressed_mesh.h"
#include "nodes/depth/organized_depth.h"
#include "nodes/eval/vertex_quality.h"
#include "nodes/extract/extract_surface.h"
#include "nodes/io/atomic_file.h"
#include "nodes/io/byte_buffer.h"
#include "nodes/io/mesh_writers.h"
#include "nodes/io/parse_util.h"
#include "nodes/io/read_point_cloud.h"
#include "nodes/io/textured_obj.h"
#include "nodes/texture/region_textures.h"
#include "options/json_report.h"
#include "runtime/error.h"
#include "runtime/half_edge_mesh.h"
#include "runtime/threads.h"
#include "tools/cli_checks.h"
#include "tools/commands.h"
#include "tools/console.h"
#include "tools/pipeline_options.h"
#include "tools/progress.h"
#include "tools/report.h"
#include "tools/run_view.h"

namespace meshflow::cli {

namespace {

struct ReconstructOptions {
  std::string input;
  std::string columns;
  std::string output;
  PipelineOptions pipeline;
  bool texture = false;
  bool quality = false;     ///< --quality: a per-vertex `quality` property (PLY output)
  std::string compress;     ///< --compress method, "" = none (a .mfc output: edgebreaker)
  std::string chunk;        ///< --chunk: "" (whole cloud), "auto" or metres
  ChunkingConfig chunking;  ///< the other --chunk* options
  std::string tiles;        ///< --tiles DIR: the mesh also as one file per chunk and an index
  ServeOptions serve;       ///< --serve: show the result in a browser
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

// What `reconstruct` does for normals with the defaults (--normals auto --orient auto): the
// report line, and the same as JSON.
std::string normals_plan(const PointCloud& cloud, nlohmann::json& plan) {
  if (cloud.has_normals()) {
    std::size_t missing = 0;
    for (const Eigen::Vector3f& n : cloud.normals)
      missing += n.allFinite() && n.squaredNorm() > 1e-12f ? 0 : 1;
    plan = {{"source", "input"}, {"missing", missing}};
    if (missing == 0) return "from the file, used as they are (--normals auto)";
    return "from the file; " + std::to_string(missing) +
           " zero or NaN, estimated from their neighbours";
  }
  const NormalOrientation o = resolve_orientation(cloud);
  plan = {{"source", "estimate"}, {"orientation", orientation_name(o)}};
  if (o != NormalOrientation::kPropagate)
    return std::string("none in the file: estimated, --orient auto = ") + orientation_name(o) +
           (cloud.has_sensor_origin ? " (towards the sensor position)"
                                    : " (organized: towards the sensor at the origin)");
  const SceneKind scene = classify_scene(cloud);
  const ComponentSide side = side_of_scene(scene);
  plan["side"] = side == ComponentSide::kAlongAxis       ? "up"
                 : side == ComponentSide::kAxisOrOutward ? "up-or-outward"
                 : side == ComponentSide::kViewOrOutward ? "camera-view-or-outward"
                                                         : "outward";
  plan["scene"] = scene_kind_name(scene);
  return std::string(
             "none in the file: estimated, --orient auto = propagate (no sensor "
             "position: consistent over neighbours, then ") +
         scene_rule(scene) + ")";
}

// -v: the settings that decide the mesh, as the stages will use them.
void print_settings(const ReconstructionConfig& c) {
  detail("settings   voxel %s, kn %d, ki %d, kd %d, extract %s, optimize",
         c.voxelize.voxel_size > 0.0f ? (std::to_string(c.voxelize.voxel_size) + " m").c_str()
                                      : "auto (3x the median point spacing)",
         c.normals.kn, c.normals.ki, c.distance.kd, extract_method_name(c.extract.method));
  for (OptimizeStep step : c.optimize.steps) detail(" %s", optimize_step_name(step));
  detail("%s\n", c.optimize.steps.empty() ? " none" : "");
}

void run_reconstruct(const ReconstructOptions& o) {
  ThreadLimit limit(o.pipeline.threads);
  ReconstructionConfig config = o.pipeline.config();
  if (!o.chunk.empty() && o.chunk != "0") {
    if (o.texture || o.quality || !o.compress.empty() || is_compressed_mesh_file(o.output))
      throw Error("--chunk", "",
                  "writes a mesh file (.ply .obj .stl .off .glb): no --texture, --quality or "
                  "--compress");
    ChunkingConfig chunking = o.chunking;
    // "auto": the chunks in flight get half of --max-memory (the rest: the seams and the
    // output's buffers), 1 GiB when none is given (ChunkingConfig::memory_budget 0).
    chunking.chunk_size = o.chunk == "auto" ? 0.0f : std::stof(o.chunk);
    chunking.memory_budget = o.pipeline.max_memory.empty() ? 0 : config.max_memory_bytes / 2;
    if (o.serve.enabled()) throw Error("--serve", "", "a reconstruction without --chunk");
    print_settings(config);
    return run_chunked_reconstruct(o.input, o.columns, o.output, o.tiles, config, chunking,
                                   limit.threads());
  }
  config.compression = compression_for(o.compress, o.output);
  const bool compressed = config.compression != MeshCompression::kNone;
  // Fail on an unwritable output before spending time on reconstruction.
  if (compressed) {
    if (!is_compressed_mesh_file(o.output))
      throw Error(o.output, "", "--compress writes a compressed mesh: give a .mfc output");
    if (o.texture) throw Error(o.output, "", "--texture and --compress exclude each other");
    io::check_output_writable(o.output);
  } else {
    const std::string ext = io::lower_extension(o.output);
    if (ext != ".ply" && ext != ".obj" && ext != ".stl" && ext != ".off" && ext != ".glb")
      throw Error(o.output, "",
                  "unknown mesh format '" + ext +
                      "' (expected .ply .obj .stl .off or .glb, or .mfc for a compressed mesh)");
    io::check_mesh_output_format(o.output);
  }
  if (o.texture && io::lower_extension(o.output) != ".obj")
    throw Error(o.output, "", "--texture writes OBJ + MTL + PNG: give an .obj output");
  if (o.quality && io::lower_extension(o.output) != ".ply")
    throw Error(o.output, "", "--quality writes a PLY vertex property: give a .ply output");
  print_settings(config);
  const std::unique_ptr<RunView> view = start_run_view(o.serve, "meshflow reconstruct");

  ReconstructionPipeline pipeline(config, 1);
  auto frame = std::make_shared<Frame>();
  frame->name = o.input;
  const std::string path = o.input, columns = o.columns;
  frame->load = [path, columns] { return io::read_point_cloud(path, columns); };
  auto progress = std::make_unique<StepProgress>();
  frame->on_stage = [&progress](const char* stage, const char* step) {
    progress->begin(stage, step);
  };
  const double t0 = monotonic_seconds();
  pipeline.run_frame(frame);
  throw_if_failed(*frame);  // an empty surface fails the extract or optimize stage
  if (o.texture && !frame->cloud.has_colors())
    throw Error(o.input, "", "--texture needs coloured points (the input has no colours)");
  std::size_t textures = 0;
  VertexSupport support;  // --quality: each vertex's distance to the points and their count
  progress->begin("write");
  if (o.texture) {
    progress->begin("texture");
    textures = write_textured(o.output, *frame, config);
  } else if (compressed) {
    io::write_file_bytes(o.output, frame->compressed);
  } else if (o.quality) {
    support = vertex_support(frame->mesh.vertices, frame->cloud.positions, frame->voxel_size);
    io::write_ply(o.output, frame->mesh, io::PlyEncoding::kBinary, frame->origin,
                  {{"quality", support.distances}, {"observations", support.observations}});
  } else {
    io::write_mesh(o.output, frame->mesh, frame->origin);
  }
  progress.reset();  // clears the progress line before the report
  const double wall = monotonic_seconds() - t0;
  if (frame->filter_counts.non_finite > 0 && !console().quiet) {
    std::fprintf(stderr, "meshflow: note: %s: dropped %zu non-finite (NaN/Inf) points\n",
                 o.input.c_str(), frame->filter_counts.non_finite);
  }
  if (console().json) {
    nlohmann::json doc = options::frame_json(*frame, wall, limit.threads());
    doc["output"] = o.output;
    doc["peak_bytes"] = chunk::peak_resident_bytes();  // the process's, as --chunk reports it
    if (o.texture) doc["textures"] = textures;
    if (compressed) doc["compressed_bytes"] = frame->compressed.size();
    if (o.quality) {
      doc["quality"] = options::distance_json(distance_stats(support.distances));
      doc["observations"] = options::observations_json(support.observations);
    }
    return print_json(doc);
  }
  print_frame_report(*frame, wall, limit.threads());
  if (o.texture) report("textures   %zu planar regions textured\n", textures);
  if (o.quality) {
    const DistanceStats q = distance_stats(support.distances);
    report(
        "quality    vertex to nearest point: mean %.3g mm, p95 %.3g mm, max %.3g mm (PLY "
        "property 'quality', metres)\n",
        1e3 * q.mean, 1e3 * q.p95, 1e3 * q.max);
    report_observations(support.observations, "points within one voxel");
  }
  if (compressed)
    report("compressed %zu bytes (%.2f bits per triangle)\n", frame->compressed.size(),
           8.0 * static_cast<double>(frame->compressed.size()) /
               static_cast<double>(frame->mesh.triangles.size()));
  report("output     %s\n", o.output.c_str());
  if (view) {
    view->frame(*frame, false);  // the stage timings
    view->result(frame->mesh, frame->origin,
                 config.compression == MeshCompression::kProgressive
                     ? frame->compressed
                     : std::vector<unsigned char>{});
    view->finish_and_serve();
  }
}

void print_info(const std::string& path, const PointCloud& cloud) {
  const std::size_t finite = count_finite_points(cloud);
  report("file        %s\n", path.c_str());
  report("points      %zu (%zu finite, %zu NaN/Inf)\n", cloud.size(), finite,
         cloud.size() - finite);
  if (cloud.is_organized()) {
    report("organized   %u x %u", cloud.width, cloud.height);
    if (const std::optional<DepthFrame> depth = depth_frame_from_organized(cloud)) {
      const PinholeIntrinsics& k = depth->intrinsics;
      report(
          ", a pinhole view: fx %.3f fy %.3f cx %.3f cy %.3f px (fuses as a depth "
          "image; --organized-as-depth)\n",
          k.fx, k.fy, k.cx, k.cy);
    } else {
      report(", not a pinhole view from the sensor origin\n");
    }
  }
  std::string fields = "x y z";
  if (cloud.has_normals()) fields += " normals";
  if (cloud.has_colors()) fields += " rgb";
  if (cloud.has_intensities()) fields += " intensity";
  report("fields      %s\n", fields.c_str());
  const Eigen::AlignedBox3f box = finite_bounds(cloud);
  if (!box.isEmpty()) {
    report("bounds min  %.4f %.4f %.4f m\n", box.min().x(), box.min().y(), box.min().z());
    report("bounds max  %.4f %.4f %.4f m\n", box.max().x(), box.max().y(), box.max().z());
    report("extent      %.4f x %.4f x %.4f m\n", box.sizes().x(), box.sizes().y(), box.sizes().z());
  }
  if (cloud.has_sensor_origin) {
    report("sensor      %.4f %.4f %.4f m\n", cloud.sensor_origin.x(), cloud.sensor_origin.y(),
           cloud.sensor_origin.z());
  }
  nlohmann::json plan;
  report("normals     %s\n", normals_plan(cloud, plan).c_str());
}

nlohmann::json info_json(const std::string& path, const PointCloud& cloud) {
  const auto vec = [](const Eigen::Vector3f& v) { return nlohmann::json{v.x(), v.y(), v.z()}; };
  const std::size_t finite = count_finite_points(cloud);
  nlohmann::json doc = {{"file", path},
                        {"points", cloud.size()},
                        {"finite_points", finite},
                        {"fields",
                         {{"normals", cloud.has_normals()},
                          {"colors", cloud.has_colors()},
                          {"intensities", cloud.has_intensities()}}}};
  if (cloud.is_organized()) {
    doc["organized"] = {{"width", cloud.width}, {"height", cloud.height}};
    if (const std::optional<DepthFrame> depth = depth_frame_from_organized(cloud)) {
      const PinholeIntrinsics& k = depth->intrinsics;
      doc["organized"]["pinhole"] = {{"fx", k.fx}, {"fy", k.fy}, {"cx", k.cx}, {"cy", k.cy}};
    }
  }
  const Eigen::AlignedBox3f box = finite_bounds(cloud);
  if (!box.isEmpty()) doc["bounds"] = {{"min", vec(box.min())}, {"max", vec(box.max())}};
  if (cloud.has_sensor_origin) doc["sensor"] = vec(cloud.sensor_origin);
  nlohmann::json plan;
  normals_plan(cloud, plan);
  doc["normals"] = plan;
  return doc;
}

void run_info(const std::string& path, const std::string& columns) {
  if (is_compressed_mesh_file(path)) return run_compressed_info(path);
  if (is_mesh_info_file(path)) return run_mesh_info(path);
  const PointCloud cloud = io::read_point_cloud(path, columns);
  if (console().json) return print_json(info_json(path, cloud));
  print_info(path, cloud);
}

void add_columns_option(CLI::App* cmd, std::string& columns) {
  cmd->add_option("--columns", columns,
                  "Text clouds: the columns' meaning, e.g. x,y,z,nx,ny,nz,r,g,b or x,y,z,skip,"
                  "intensity (default: from a header line, else detected)");
}

}  // namespace

void add_reconstruct_options(CLI::App* cmd) {
  auto opts = std::make_shared<ReconstructOptions>();
  cmd->add_option("input", opts->input, "Point cloud: .ply .pcd .las .xyz .txt .pts .asc .csv .3d")
      ->required();
  cmd->add_option("-o,--output", opts->output, "Output mesh: .ply .obj .stl .off .glb .mfc")
      ->required();
  add_columns_option(cmd, opts->columns);
  add_compress_option(cmd, opts->compress);
  add_pipeline_options(cmd, opts->pipeline);
  add_serve_options(cmd, opts->serve);
  add_console_flags(cmd, true);
  cmd->add_flag("--texture", opts->texture,
                "Texture planar regions from the points' colours (OBJ + MTL + PNG output)");
  cmd->add_flag("--quality", opts->quality,
                "Write each vertex's distance to the nearest input point (metres, after the "
                "filter stage) and the number of input points within one voxel of it as the "
                "float vertex properties 'quality' and 'observations' (PLY output)");
  cmd->add_option("--chunk", opts->chunk,
                  "Out of core: stream the input into chunks of this edge (metres) on disk and "
                  "mesh them a few at a time, seams welded exactly; 'auto': the edge that lets "
                  "the chunks in flight fit half of --max-memory, 1 GiB when none is given "
                  "(default: whole cloud in memory)")
      ->check(CLI::IsMember({"auto"}) | number_in(0, 1e6))
      ->excludes("--close");  // the diffusion needs the whole object's grid
  cmd->add_option("--chunk-overlap", opts->chunking.overlap_voxels,
                  "Voxels of points each chunk sees beyond its own cells")
      ->check(number_in(1, 64))
      ->capture_default_str();
  cmd->add_option("--chunk-dir", opts->chunking.directory,
                  "Where the chunk files go (default: the system's temporary directory)");
  cmd->add_option("--chunks-in-flight", opts->chunking.in_flight, "Chunks meshed at once")
      ->check(number_in(1, 64))
      ->capture_default_str();
  cmd->add_flag("--finish-after-stitch{false}", opts->chunking.finish_in_place,
                "Flip, trim the rim, clean and fill holes once on the stitched mesh instead "
                "of per chunk with seams held fixed (the single-process mesh but for a few "
                "triangles; serial, and the whole mesh several times in memory)");
  cmd->add_option(
         "--tiles", opts->tiles,
         "With --chunk: also write the mesh as one glTF file per chunk (DIR/tile_I_J_K.glb), "
         "each also at coarser levels from the progressive coder (tile_I_J_K_lodL.glb), and "
         "their index DIR/tiles.json (and DIR/tileset.json, 3D Tiles 1.1), for viewers that load "
         "what they look at")
      ->needs("--chunk");
  cmd->callback([opts] { run_reconstruct(*opts); });
}

void add_info_options(CLI::App* cmd) {
  auto path = std::make_shared<std::string>();
  cmd->add_option("file", *path,
                  "Point cloud file, a mesh (.ply with faces, .obj .off .stl .glb: area, volume, "
                  "genus, components, borders, manifoldness) or a compressed mesh (.mfc)")
      ->required();
  auto columns = std::make_shared<std::string>();
  add_columns_option(cmd, *columns);
  add_console_flags(cmd, true);
  cmd->callback([path, columns] { run_info(*path, *columns); });
}

}  // namespace meshflow::cli
