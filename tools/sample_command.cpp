// meshflow sample OBJECT -o CLOUD.ply: points drawn uniformly over one of meshflow's closed test
// objects (nodes/synthetic/closed_objects.h), for trying and measuring object reconstruction
// without a scanner; `meshflow eval MESH --object OBJECT` measures against its exact surface.
// With --orbit N: N depth frames of a camera circling the object, written as a TUM RGB-D
// directory (for `meshflow run DIR --fuse`, and for other tools on the same frames). With
// --scan N: N views from one ring merged into one cloud without normals (a turntable scan,
// --outliers added), the input of `reconstruct --close`.
// `sample city`: a large scanned site (terrain and buildings) streamed to PLY, for the
// out-of-core path (`reconstruct --chunk`).

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "nodes/io/mesh_writers.h"
#include "nodes/io/ply_point_writer.h"
#include "nodes/io/tum_writer.h"
#include "nodes/synthetic/city_scene.h"
#include "nodes/synthetic/closed_objects.h"
#include "nodes/synthetic/depth_sequence.h"
#include "nodes/synthetic/object_orbit.h"
#include "nodes/synthetic/object_scan.h"
#include "runtime/error.h"
#include "tools/cli_checks.h"
#include "tools/commands.h"
#include "tools/console.h"

namespace meshflow::cli {
namespace {

struct SampleOptions {
  std::string object;
  std::string output;
  std::size_t points = 100000;
  float noise = 0.0f;  ///< fraction of the bounding-box diagonal
  bool normals = false;
  std::uint32_t seed = 1;
  int orbit = 0;                 ///< > 0: depth frames of a camera circling the object
  int scan = 0;                  ///< > 0: views on one ring merged into one cloud (object_scan.h)
  float outliers = 0.0f;         ///< --scan: uniform outliers, fraction of the surface points
  std::string size = "640x480";  ///< their image size
  float depth_noise = 0.001f;    ///< their range noise, metres
  float site = synthetic::CitySceneConfig{}.size;  ///< city: side of the site, metres
};

// The large scene, streamed to a binary PLY batch by batch (any number of points).
void write_city(const SampleOptions& o) {
  synthetic::CitySceneConfig config;
  config.size = o.site;
  config.seed = o.seed;
  const synthetic::CityScene city(config);
  io::PlyPointWriter writer(o.output, o.points, o.normals, false);
  const float noise = o.noise * city.bounds().diagonal().norm();
  city.sample(o.points, noise, [&](const PointCloud& batch) {
    if (o.normals) return writer.append(batch);
    PointCloud positions;
    positions.positions = batch.positions;
    writer.append(positions);
  });
  writer.finish();
  const Eigen::Vector3f size = city.bounds().sizes();
  report("scene      city: %.0f x %.0f x %.1f m, %zu buildings, surface %.0f m^2\n", size.x(),
         size.y(), size.z(), city.buildings().size(), city.area());
  report("points     %zu%s, %.1f per m^2 (spacing about %.3f m), noise %.3g m\n", o.points,
         o.normals ? " with exact normals" : "", static_cast<double>(o.points) / city.area(),
         std::sqrt(city.area() / static_cast<double>(o.points)), noise);
  report("output     %s\n", o.output.c_str());
}

void write_orbit(const SampleOptions& o, const synthetic::ClosedObject& object) {
  synthetic::ObjectOrbitConfig config;
  config.frames = o.orbit;
  config.noise_sigma = o.depth_noise;
  int width = 0, height = 0;
  if (std::sscanf(o.size.c_str(), "%dx%d", &width, &height) != 2 || width < 8 || height < 8 ||
      width > 8192 || height > 8192) {
    throw Error("--size", o.size, "expected WIDTHxHEIGHT, each 8..8192 pixels");
  }
  config.intrinsics = synthetic::scaled_default_camera(width, height);
  const auto sequence = synthetic::make_object_orbit(object, config);
  io::write_tum_directory(*sequence, o.output);
  report("object     %s: diagonal %.4f m\n", object.name.c_str(), object.diagonal());
  report("frames     %d depth + colour frames %dx%d circling it, range noise %.3g m\n", o.orbit,
         width, height, o.depth_noise);
  report("output     %s (TUM RGB-D layout: depth/, rgb/, groundtruth.txt, camera.json)\n",
         o.output.c_str());
}

// A turntable-like scan: o.scan views on one ring, merged without normals or sensor, plus
// o.outliers x the points scattered in the bounding box (written after the surface points).
void write_scan(const SampleOptions& o, const synthetic::ClosedObject& object) {
  synthetic::ObjectScanConfig config;
  config.views = o.scan;
  config.noise_sigma = o.depth_noise;
  config.outlier_fraction = o.outliers;
  config.seed = o.seed;
  const synthetic::ObjectScan scan = synthetic::scan_object(object, config);
  TriangleMesh points;
  points.vertices = scan.cloud.positions;
  io::write_ply(o.output, points);
  report("object     %s: diagonal %.4f m; 1 %% of the diagonal is %.4f m\n", object.name.c_str(),
         object.diagonal(), 0.01 * object.diagonal());
  report(
      "scan       %d views on one ring, range noise %.3g m: %zu surface points, %zu outliers "
      "(the last ones)\n",
      o.scan, o.depth_noise, scan.cloud.size() - scan.outliers, scan.outliers);
  report("output     %s\n", o.output.c_str());
}

void run_sample(const SampleOptions& o) {
  if (o.object == "city") {
    if (o.orbit > 0 || o.scan > 0)
      throw Error(o.orbit > 0 ? "--orbit" : "--scan", "city", "the city is sampled as points only");
    return write_city(o);
  }
  const synthetic::ClosedObject object = *synthetic::closed_test_object(o.object);
  if (o.orbit > 0) {
    write_orbit(o, object);
    return;
  }
  if (o.scan > 0) return write_scan(o, object);
  const PointCloud cloud = object.sample(o.points, o.noise * object.diagonal(), o.seed);
  TriangleMesh points;  // a PLY of vertices only
  points.vertices = cloud.positions;
  if (o.normals) points.normals = cloud.normals;
  io::write_ply(o.output, points);
  const Eigen::Vector3f size = object.bounds.sizes();
  report("object     %s: %.3f x %.3f x %.3f m, diagonal %.4f m, area %.4f m^2\n",
         object.name.c_str(), size.x(), size.y(), size.z(), object.diagonal(), object.area());
  report("points     %zu%s, noise %.3g m; 1 %% of the diagonal is %.4f m\n", cloud.size(),
         o.normals ? " with exact normals" : "", o.noise * object.diagonal(),
         0.01 * object.diagonal());
  report("output     %s\n", o.output.c_str());
}

}  // namespace

std::vector<std::string> closed_object_names() {
  std::vector<std::string> names;
  for (const synthetic::ClosedObject& o : synthetic::all_test_objects()) names.push_back(o.name);
  return names;
}

namespace {
std::vector<std::string> sample_names() {
  std::vector<std::string> names = closed_object_names();
  names.push_back("city");
  return names;
}
}  // namespace

void add_sample_options(CLI::App* cmd) {
  auto opts = std::make_shared<SampleOptions>();
  cmd->add_option("object", opts->object,
                  "sphere, torus, l-shape, chamfered-cube, box-with-hole, box, thin-plate, or "
                  "city (a large terrain with buildings, streamed: any number of points)")
      ->required()
      ->check(CLI::IsMember(sample_names()));
  cmd->add_option("-o,--output", opts->output,
                  "Output point cloud (.ply), or directory with --orbit")
      ->required();
  cmd->add_option("--points", opts->points, "Number of points")->check(number_in(1, 1e9));
  cmd->add_option("--noise", opts->noise,
                  "Gaussian noise, as a fraction of the bounding-box diagonal (e.g. 0.002)")
      ->check(number_in(0, 1));
  cmd->add_flag("--normals", opts->normals, "Write the exact outward normals too");
  cmd->add_option("--seed", opts->seed, "Random seed")->check(number_in(0, 4294967295.0));
  cmd->add_option("--orbit", opts->orbit,
                  "Instead of points: this many depth frames of a camera circling the object, "
                  "written as a TUM RGB-D directory")
      ->check(number_in(0, 100000));
  auto* scan = cmd->add_option("--scan", opts->scan,
                               "Instead of uniform points: this many depth views from one ring "
                               "25 degrees above the object (200 x 150 pixels), merged into one "
                               "cloud without normals or sensor (as a turntable scanner's; the "
                               "underside unseen)")
                   ->check(number_in(0, 1000))
                   ->excludes("--orbit");
  cmd->add_option("--outliers", opts->outliers,
                  "With --scan: points scattered uniformly in the bounding box, as a fraction "
                  "of the surface points (e.g. 0.005)")
      ->check(number_in(0, 1))
      ->needs(scan);
  cmd->add_option("--size", opts->size, "Image size of the --orbit frames (WIDTHxHEIGHT)");
  cmd->add_option("--depth-noise", opts->depth_noise,
                  "Range noise of the --orbit and --scan views, metres (Gaussian sigma)")
      ->check(number_in(0, 1));
  cmd->add_option("--site", opts->site, "city: side of the square site, metres")
      ->check(number_in(10, 20000));
  add_console_flags(cmd, false);
  cmd->callback([opts] { run_sample(*opts); });
}

}  // namespace meshflow::cli
