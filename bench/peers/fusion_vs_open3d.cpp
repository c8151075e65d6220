// meshflow_fusion_vs_open3d: one object's orbit fused by meshflow (FusionPipeline, the defaults
// of `meshflow run --fuse`) and by Open3D 0.16 (ScalableTSDFVolume, integrate + extract) at the
// same voxel and truncation, both meshes measured against the object's exact surface, and the
// truth samples one mesh covers and the other misses broken down by meshflow's map there.
//
//   meshflow_fusion_vs_open3d [--object perforated-box] [--voxel 0.01] [--truncation 4]
//       [--frames 24] [--width 640] [--cache DIR] [--behind B] [--no-carve] [--drop-edges]
//       [--no-optimize] [--along-ray] [--min-weight W] [--tau 0.5] [--patches]
//
// Objects: perforated-box and pocketed-block (nodes/synthetic/perforated_box.h), sieve (below)
// or a built-in closed test object. --tau: the completeness threshold in voxels (also reported
// at twice it); --patches: the differences per patch of the object as well. --cache DIR: the
// rendered frames as a TUM RGB-D directory, written once and read back on later runs.
// Completeness: of 200 000 points on the exact surface, the share within half a voxel of the
// mesh (and the mean distance, a fraction of the diagonal as in bench/python); accuracy: the
// mesh's area-sampled mean distance to the surface. Open3D runs on the same frames (depth
// quantised to 1 mm, 1 mm noise) with its own rules: a voxel is updated wherever it lies less
// than a truncation behind the measured depth (along the ray), and a cell is meshed only when
// all eight corners were observed.

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

#include "graph/fusion_pipeline.h"
#include "graph/sequence_runner.h"
#include "nodes/eval/truth_eval.h"
#include "nodes/io/sequence.h"
#include "nodes/io/tum_writer.h"
#include "nodes/search/mesh_distance_index.h"
#include "nodes/synthetic/depth_sequence.h"
#include "nodes/synthetic/object_orbit.h"
#include "nodes/synthetic/perforated_box.h"

namespace meshflow {
namespace {

struct Options {
  std::string object = "perforated-box";
  float voxel = 0.01f, truncation = 4.0f, behind = TsdfConfig{}.behind_voxels;
  float min_weight = 0.0f;
  float tau_voxels = 0.5f;  // completeness threshold
  bool patches = false;     // also break the differences down by the object's patch
  int frames = 24, width = 640;
  std::string cache;
  bool carve = true, keep_edges = true, optimize = true, along_ray = false;
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

// Each truth point's distance to the mesh's surface.
std::vector<float> distances_to(const TriangleMesh& mesh, const std::vector<Eigen::Vector3f>& at) {
  std::vector<float> out(at.size(), std::numeric_limits<float>::infinity());
  if (mesh.triangles.empty()) return out;
  const MeshDistanceIndex index(mesh);
  tbb::parallel_for(std::size_t{0}, at.size(),
                    [&](std::size_t i) { out[i] = index.closest(at[i]).distance; });
  return out;
}

void report(const char* tool, const TriangleMesh& mesh, const std::vector<float>& to_mesh,
            const synthetic::ClosedObject& object, float tau) {
  const double diagonal = object.diagonal();
  const double accuracy =
      evaluate_against_truth(
          mesh, [&](const Eigen::Vector3f& p) { return object.distance(p); }, 200000)
          .area.mean /
      diagonal;
  double sum = 0.0;
  std::size_t within = 0, within_voxel = 0;
  for (float d : to_mesh) {
    sum += std::min(d, 1.0f);
    within += d <= tau ? 1 : 0;
    within_voxel += d <= 2.0f * tau ? 1 : 0;
  }
  const double n = static_cast<double>(to_mesh.size());
  std::printf(
      "%-9s accuracy %.3e  completeness mean %.3e  within %.1f mm %.4f  within %.1f mm %.4f  "
      "triangles %zu  border edges %zu\n",
      tool, accuracy, sum / n / diagonal, 1e3 * tau, static_cast<double>(within) / n, 2e3 * tau,
      static_cast<double>(within_voxel) / n, mesh.triangles.size(),
      edge_statistics(mesh).boundary_edges);
}

// What meshflow's map holds in the cell around p.
enum Cell { kNothing, kPartlyObserved, kAllInFront, kAllBehind, kSignChange, kCellKinds };
const char* const kCellNames[kCellKinds] = {"no corner observed", "some corners unobserved",
                                            "all observed, in front (+)",
                                            "all observed, behind (-)", "a sign change (meshed)"};

Cell cell_at(const TsdfMap& map, const Eigen::Vector3f& p, float min_weight) {
  const float voxel = map.config().voxel_size;
  const Eigen::Vector3i base = (p / voxel).array().floor().cast<int>();
  int observed = 0, in_front = 0;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3i v = base + Eigen::Vector3i(c & 1, (c >> 1) & 1, (c >> 2) & 1);
    const Eigen::Vector3i block = (v.cast<float>() / kTsdfBlockSide).array().floor().cast<int>();
    const TsdfBlock* b = map.find(block);
    if (b == nullptr) continue;
    const Eigen::Vector3i local = v - block * kTsdfBlockSide;
    const TsdfVoxel& voxel_at = b->voxels[static_cast<std::size_t>(
        local.x() + kTsdfBlockSide * (local.y() + kTsdfBlockSide * local.z()))];
    if (!(voxel_at.weight > min_weight)) continue;
    ++observed;
    in_front += voxel_at.distance >= 0.0f ? 1 : 0;
  }
  if (observed == 0) return kNothing;
  if (in_front > 0 && in_front < observed) return kSignChange;
  if (observed < 8) return kPartlyObserved;
  return in_front == 8 ? kAllInFront : kAllBehind;
}

int run(int argc, char** argv) {
  const Options o = parse(argc, argv);
  const synthetic::ClosedObject object = object_named(o.object);
  const auto sequence = orbit(object, o);
  const float tau = o.tau_voxels * o.voxel;
  std::printf(
      "%s: %zu frames, voxel %.3f m, truncation %.1f voxels, meshflow band behind %.1f%s%s%s\n",
      object.name.c_str(), sequence->size(), o.voxel, o.truncation,
      std::min(o.behind, o.truncation), o.carve ? "" : ", no carving",
      o.keep_edges ? "" : ", occlusion edges dropped", o.optimize ? "" : ", no clean-up");
  const auto pipeline = fuse_meshflow(*sequence, o);
  TsdfExtractStats stats;
  const TriangleMesh ours = pipeline->extract_mesh(&stats);
  const TsdfMap& map = pipeline->map();
  std::printf("meshflow cells: %zu meshed (%zu completed behind), %zu left out\n",
              stats.cells.cells_meshed, stats.cells.cells_completed, stats.cells.cells_left_out);
  const TriangleMesh theirs = fuse_open3d(*sequence, o);
  const std::vector<Eigen::Vector3f> truth = object.sample(200000, 0.0f, 7).positions;
  const std::vector<float> to_ours = distances_to(ours, truth);
  const std::vector<float> to_theirs = distances_to(theirs, truth);
  report("meshflow", ours, to_ours, object, tau);
  report("Open3D", theirs, to_theirs, object, tau);
  std::size_t kinds[2][kCellKinds] = {};
  std::size_t only[2] = {};
  std::vector<std::size_t> by_patch[2];
  by_patch[0].assign(object.patches.size(), 0);
  by_patch[1].assign(object.patches.size(), 0);
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const bool ours_has = to_ours[i] <= tau, theirs_has = to_theirs[i] <= tau;
    if (ours_has == theirs_has) continue;
    const int side = theirs_has ? 0 : 1;  // 0: Open3D keeps, meshflow drops
    ++only[side];
    ++kinds[side][cell_at(map, truth[i], o.min_weight)];
    if (o.patches) {
      std::size_t nearest = 0;
      for (std::size_t k = 1; k < object.patches.size(); ++k)
        if (object.patches[k].distance(truth[i]) < object.patches[nearest].distance(truth[i]))
          nearest = k;
      ++by_patch[side][nearest];
    }
  }
  const char* const sides[2] = {"Open3D keeps, meshflow drops", "meshflow keeps, Open3D drops"};
  for (int side = 0; side < 2; ++side) {
    std::printf("%s: %zu of %zu truth points (%.2f %%); meshflow's cell there:\n", sides[side],
                only[side], truth.size(), 100.0 * static_cast<double>(only[side]) / 200000.0);
    for (int k = 0; k < kCellKinds; ++k)
      std::printf("  %-28s %zu\n", kCellNames[k], kinds[side][k]);
    if (o.patches) {
      std::printf("  by patch:");
      for (std::size_t k = 0; k < by_patch[side].size(); ++k)
        if (by_patch[side][k] > 0) std::printf(" %zu:%zu", k, by_patch[side][k]);
      std::printf("\n");
    }
  }
  return 0;
}

}  // namespace
}  // namespace meshflow

int main(int argc, char** argv) { return meshflow::run(argc, argv); }
