// meshflow_fusion_vs_open3d: one input's frames fused by meshflow (FusionPipeline, the defaults
// of `meshflow run --fuse`) and by Open3D 0.16 (ScalableTSDFVolume, integrate + extract) at the
// same voxel and truncation, both meshes measured against one reference, and the reference
// points one mesh covers and the other misses broken down by meshflow's map there.
//
//   meshflow_fusion_vs_open3d [--object perforated-box] [--voxel 0.01] [--truncation 4]
//       [--frames 24] [--width 640] [--cache DIR] [--behind B] [--no-carve] [--drop-edges]
//       [--no-optimize] [--along-ray] [--min-weight W] [--tau 0.5] [--patches]
//   meshflow_fusion_vs_open3d --table [--voxel 0.01] [--truncation 4] [--frames 24]
//
// Inputs: an orbit of 24 views (1 mm noise, `meshflow sample OBJECT --orbit 24`) around
// perforated-box or pocketed-block (nodes/synthetic/perforated_box.h), sieve (below) or a
// built-in closed test object, against its exact surface; or "redwood": the Redwood RGB-D frames
// in $MESHFLOW_DATA/rgbd_redwood (default ../shared/data), against the frames themselves.
// Completeness: the mean distance of the reference points to the mesh and the shares within
// --tau voxels (default half a voxel) and twice that; reference: 200 000 points on the exact
// surface, or every second pixel of every second row of every Redwood frame with a depth in
// (0.1, 10) m, back-projected with the frame's pose (what bench/python/bench_fusion_vs_open3d.py
// used). Accuracy: the mesh's area-sampled mean distance to the exact surface; for Redwood the
// mean distance of the mesh's vertices to the nearest reference point (`meshflow eval
// --reference`). Objects' distances are fractions of the diagonal, Redwood's millimetres.
// --patches: the differences per patch of the object as well. --cache DIR: the rendered frames
// as a TUM RGB-D directory, written once and read back on later runs. --table: every input of
// bench/RESULTS.md's fused-map table (meshflow projective and along-ray, Open3D), one Markdown
// row each. Open3D runs on the same frames (depth in mm) with its own rules: a voxel of every
// 16^3 unit near a measured point is updated wherever it lies less than a truncation behind the
// measured depth (along the ray), and a cell is meshed only when all eight corners were observed.

#include <open3d/camera/PinholeCameraIntrinsic.h>
#include <open3d/geometry/Image.h>
#include <open3d/geometry/RGBDImage.h>
#include <open3d/geometry/TriangleMesh.h>
#include <open3d/pipelines/integration/ScalableTSDFVolume.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "bench/peers/fused_map_measures.h"
#include "graph/fusion_pipeline.h"
#include "graph/sequence_runner.h"
#include "nodes/io/sequence.h"
#include "nodes/io/tum_writer.h"
#include "nodes/synthetic/depth_sequence.h"
#include "nodes/synthetic/object_orbit.h"
#include "nodes/synthetic/perforated_box.h"

namespace meshflow {
namespace {

using fusion_peer::breakdown;
using fusion_peer::measure;
using fusion_peer::Measures;
using fusion_peer::report;
using fusion_peer::Scene;

struct Options {
  std::string object = "perforated-box";
  float voxel = 0.01f, truncation = 4.0f, behind = TsdfConfig{}.behind_voxels;
  float min_weight = 0.0f;
  float tau_voxels = 0.5f;  // completeness threshold
  bool patches = false;     // also break the differences down by the object's patch
  int frames = 24, width = 640;
  std::string cache;
  bool carve = true, keep_edges = true, optimize = true, along_ray = false, table = false;
};

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--object")
      o.object = value();
    else if (a == "--voxel")
      o.voxel = std::stof(value());
    else if (a == "--truncation")
      o.truncation = std::stof(value());
    else if (a == "--behind")
      o.behind = std::stof(value());
    else if (a == "--min-weight")
      o.min_weight = std::stof(value());
    else if (a == "--frames")
      o.frames = std::stoi(value());
    else if (a == "--width")
      o.width = std::stoi(value());
    else if (a == "--cache")
      o.cache = value();
    else if (a == "--no-carve")
      o.carve = false;
    else if (a == "--drop-edges")
      o.keep_edges = false;
    else if (a == "--no-optimize")
      o.optimize = false;
    else if (a == "--along-ray")
      o.along_ray = true;
    else if (a == "--tau")
      o.tau_voxels = std::stof(value());
    else if (a == "--patches")
      o.patches = true;
    else if (a == "--table")
      o.table = true;
    else {
      std::fprintf(stderr, "unknown argument %s (see the file's header)\n", a.c_str());
      std::exit(2);
    }
  }
  return o;
}

// "sieve": a 0.6 x 0.6 x 0.2 m slab with a 5 x 5 grid of narrow holes in its top, 2-3.5 voxels
// across at 1 cm, through and blind in turn (a second held-out object, bench only).
synthetic::ClosedObject sieve_object() {
  synthetic::PerforatedBox box;
  box.center = Eigen::Vector3f(0.017f, 0.004f, -0.013f);
  box.half_size = Eigen::Vector3f(0.3f, 0.3f, 0.1f);
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) {
      const int n = 5 * i + j;
      const float radius = 0.02f + 0.005f * static_cast<float>(n % 4);
      const float depth = n % 2 == 0 ? 0.2f : 0.06f + 0.02f * static_cast<float>(n % 3);
      box.holes.push_back({2, 1.0f, -0.22f + 0.11f * static_cast<float>(i),
                           -0.22f + 0.11f * static_cast<float>(j), radius, depth});
    }
  return synthetic::perforated_box_object(box, "sieve");
}

synthetic::ClosedObject object_named(const std::string& name) {
  if (name == "perforated-box") return synthetic::perforated_box_object();
  if (name == "sieve") return sieve_object();
  if (name == "pocketed-block") return synthetic::pocketed_block_object();
  if (auto o = synthetic::closed_test_object(name)) return *o;
  std::fprintf(stderr, "unknown object %s\n", name.c_str());
  std::exit(2);
}

// The orbit's frames, rendered or read from --cache.
std::unique_ptr<io::Sequence> orbit(const synthetic::ClosedObject& object, const Options& o) {
  synthetic::ObjectOrbitConfig config;
  config.frames = o.frames;
  config.intrinsics = synthetic::scaled_default_camera(o.width, o.width * 3 / 4);
  auto rendered = synthetic::make_object_orbit(object, config);
  if (o.cache.empty()) return rendered;
  if (!std::filesystem::exists(o.cache + "/depth.txt")) io::write_tum_directory(*rendered, o.cache);
  return io::open_sequence(o.cache);
}

// Fuses the sequence as `meshflow run --fuse` would with o's settings; the pipeline holds the map.
std::unique_ptr<FusionPipeline> fuse_meshflow(const io::Sequence& sequence, const Options& o) {
  FusionConfig config;
  config.tsdf.voxel_size = o.voxel;
  config.tsdf.truncation_voxels = o.truncation;
  config.tsdf.behind_voxels = std::min(o.behind, o.truncation);
  config.tsdf.carve_free_space = o.carve;
  if (o.along_ray) config.tsdf.integrator = TsdfIntegrator::kAlongRay;
  config.keep_occlusion_edges = o.keep_edges;
  config.min_weight = o.min_weight;
  if (!o.optimize) config.frames.optimize.steps.clear();
  auto pipeline = std::make_unique<FusionPipeline>(config, 2);
  run_sequence(*pipeline, sequence, {}, [](const Frame& f) {
    if (!f.ok()) std::fprintf(stderr, "frame %s: %s\n", f.name.c_str(), f.error.c_str());
  });
  return pipeline;
}

open3d::geometry::Image to_open3d(const Image& image, int channels, int bytes_per_channel) {
  open3d::geometry::Image out;
  out.Prepare(image.cols(), image.rows(), channels, bytes_per_channel);
  std::copy_n(image.data(), image.pixels() * bytes_per_pixel(image.format()), out.data_.data());
  return out;
}

TriangleMesh fuse_open3d(const io::Sequence& sequence, const Options& o) {
  open3d::pipelines::integration::ScalableTSDFVolume volume(
      o.voxel, o.truncation * o.voxel, open3d::pipelines::integration::TSDFVolumeColorType::RGB8);
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    const DepthFrame f = sequence.frame(i).load_depth();
    const PinholeIntrinsics& k = f.intrinsics;
    const open3d::camera::PinholeCameraIntrinsic intrinsic(k.width, k.height, k.fx, k.fy, k.cx,
                                                           k.cy);
    const auto rgbd = open3d::geometry::RGBDImage::CreateFromColorAndDepth(
        to_open3d(f.color, 3, 1), to_open3d(f.depth, 1, 2), f.depth_scale,
        /*depth_trunc=*/1e3, /*convert_rgb_to_intensity=*/false);
    volume.Integrate(*rgbd, intrinsic, f.T_world_camera.inverse().matrix().cast<double>());
  }
  const auto extracted = volume.ExtractTriangleMesh();
  TriangleMesh mesh;
  for (const Eigen::Vector3d& v : extracted->vertices_) mesh.vertices.push_back(v.cast<float>());
  for (const Eigen::Vector3i& t : extracted->triangles_)
    mesh.triangles.push_back(Triangle{static_cast<std::uint32_t>(t[0]),
                                      static_cast<std::uint32_t>(t[1]),
                                      static_cast<std::uint32_t>(t[2])});
  return mesh;
}

Scene make_scene(const std::string& name, const Options& o) {
  Scene scene;
  scene.name = name;
  if (name == "redwood") {
    const char* data = std::getenv("MESHFLOW_DATA");
    scene.sequence =
        io::open_sequence(std::string(data ? data : "../shared/data") + "/rgbd_redwood");
    scene.reference = fusion_peer::frame_points(*scene.sequence);
    scene.unit = 1e-3;
    scene.seen.assign(scene.reference.size(), 1);  // every point is a measurement
    return scene;
  }
  scene.object = object_named(name);
  scene.sequence = orbit(*scene.object, o);
  scene.reference = scene.object->sample(200000, 0.0f, 7).positions;
  scene.unit = scene.object->diagonal();
  scene.seen = fusion_peer::seen_by_frames(*scene.sequence, scene.reference, o.voxel);
  return scene;
}

// One input in detail: both tools' measures and the breakdown.
int run_one(const Options& o) {
  const Scene scene = make_scene(o.object, o);
  const float tau = o.tau_voxels * o.voxel;
  std::printf(
      "%s: %zu frames, voxel %.3f m, truncation %.1f voxels, meshflow band behind %.1f%s%s%s; "
      "distances in %s\n",
      scene.name.c_str(), scene.sequence->size(), o.voxel, o.truncation,
      std::min(o.behind, o.truncation), o.carve ? "" : ", no carving",
      o.keep_edges ? "" : ", occlusion edges dropped", o.optimize ? "" : ", no clean-up",
      scene.object ? "fractions of the diagonal" : "mm");
  const auto pipeline = fuse_meshflow(*scene.sequence, o);
  TsdfExtractStats stats;
  const TriangleMesh ours = pipeline->extract_mesh(&stats);
  std::printf("meshflow cells: %zu meshed (%zu completed behind), %zu left out\n",
              stats.cells.cells_meshed, stats.cells.cells_completed, stats.cells.cells_left_out);
  const Measures our = measure(ours, scene, tau);
  const Measures their = measure(fuse_open3d(*scene.sequence, o), scene, tau);
  report(o.along_ray ? "along-ray" : "meshflow", our, tau);
  report("Open3D", their, tau);
  breakdown(scene, pipeline->map(), our, their, tau, o.min_weight, o.patches);
  return 0;
}

// " | a | b | c" with the best of the three figures `v` in bold (the least, with `most` the
// largest; every one that prints as the best does); `text`: how each is printed.
std::string row_cells(const std::string (&text)[3], const double (&v)[3], bool most) {
  int best = 0;
  for (int k = 1; k < 3; ++k)
    if (most ? v[k] > v[best] : v[k] < v[best]) best = k;
  std::string out;
  for (int k = 0; k < 3; ++k)
    out += text[k] == text[best] ? " | **" + text[k] + "**" : " | " + text[k];
  return out;
}

// The three figures printed with `format`, the least in bold.
std::string row_cells(const double (&v)[3], const char* format) {
  std::string text[3];
  for (int k = 0; k < 3; ++k) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, format, v[k]);
    text[k] = buffer;
  }
  return row_cells(text, v, false);
}

// bench/RESULTS.md's fused-map table: every input, meshflow projective and along-ray and Open3D.
int run_table(const Options& o) {
  const float tau = o.tau_voxels * o.voxel;
  std::printf(
      "| input | accuracy meshflow | along-ray | Open3D | completeness meshflow | along-ray | "
      "Open3D | within %g / %g voxel meshflow | along-ray | Open3D | border edges meshflow / "
      "Open3D |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
      o.tau_voxels, 2.0 * o.tau_voxels);
  const char* const inputs[] = {"sphere",        "torus",  "l-shape",    "chamfered-cube",
                                "box-with-hole", "box",    "thin-plate", "perforated-box",
                                "sieve",         "redwood"};
  for (const char* name : inputs) {
    Options projective = o, along_ray = o;
    if (!o.cache.empty()) projective.cache = along_ray.cache = o.cache + "/" + name;
    along_ray.along_ray = true;
    const Scene scene = make_scene(name, projective);
    const Measures m[3] = {
        measure(fuse_meshflow(*scene.sequence, projective)->extract_mesh(), scene, tau),
        measure(fuse_meshflow(*scene.sequence, along_ray)->extract_mesh(), scene, tau),
        measure(fuse_open3d(*scene.sequence, o), scene, tau)};
    char label[96];
    if (scene.object)
      std::snprintf(label, sizeof label, "%s (diag. %.2f m)", name, scene.unit);
    else
      std::snprintf(label, sizeof label, "Redwood, %zu frames (mm, against the frames)",
                    scene.sequence->size());
    const char* format = scene.object ? "%.3e" : "%.2f";
    const double accuracy[3] = {m[0].accuracy, m[1].accuracy, m[2].accuracy};
    const double completeness[3] = {m[0].completeness, m[1].completeness, m[2].completeness};
    const double within_twice[3] = {m[0].within_twice, m[1].within_twice, m[2].within_twice};
    std::string within[3];  // "share within tau / within twice tau", the latter ranked
    for (int k = 0; k < 3; ++k) {
      char text[32];
      std::snprintf(text, sizeof text, "%.4f / %.4f", m[k].within, m[k].within_twice);
      within[k] = text;
    }
    std::printf("| %s%s%s%s | %zu / %zu |\n", label, row_cells(accuracy, format).c_str(),
                row_cells(completeness, format).c_str(),
                row_cells(within, within_twice, true).c_str(), m[0].border_edges,
                m[2].border_edges);
    std::fflush(stdout);
  }
  return 0;
}

int run(int argc, char** argv) {
  const Options o = parse(argc, argv);
  return o.table ? run_table(o) : run_one(o);
}

}  // namespace
}  // namespace meshflow

int main(int argc, char** argv) { return meshflow::run(argc, argv); }
