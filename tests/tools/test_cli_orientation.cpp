// Which way a reconstruction faces when the input carries no sensor position (issue 55): a
// camera-frame cloud written as Open3D writes it, an airborne LAS tile, meshflow's closed
// objects; and the user's own choice (--orient up / down / flip / viewpoint in world
// coordinates).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>

#include "cli_runner.h"
#include "nodes/io/mesh_readers.h"
#include "nodes/io/ply_point_writer.h"
#include "nodes/io/read_point_cloud.h"
#include "test_support.h"

namespace meshflow {
namespace {

// A LAS 1.2 file of point format 0 holding `points` (world coordinates, millimetre resolution).
std::string las_file_of(const std::vector<Eigen::Vector3d>& points) {
  std::string h(227, '\0');
  const auto put = [&h](std::size_t at, const auto& v) { std::memcpy(&h[at], &v, sizeof v); };
  std::memcpy(&h[0], "LASF", 4);
  h[24] = 1;
  h[25] = 2;
  put(94, std::uint16_t{227});
  put(96, std::uint32_t{227});
  h[104] = 0;
  put(105, std::uint16_t{20});
  put(107, static_cast<std::uint32_t>(points.size()));
  Eigen::Vector3d lo = points.front(), hi = points.front();
  for (const Eigen::Vector3d& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  for (int k = 0; k < 3; ++k) {
    put(131 + 8 * k, 0.001);  // scale
    put(155 + 8 * k, lo[k]);  // offset
    put(179 + 16 * k, hi[k]);
    put(187 + 16 * k, lo[k]);
  }
  for (const Eigen::Vector3d& p : points) {
    std::string r(20, '\0');
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<std::int32_t>(std::lround((p[k] - lo[k]) / 0.001));
      std::memcpy(&r[static_cast<std::size_t>(4 * k)], &v, 4);
    }
    h += r;
  }
  return h;
}

// A hilly 50 x 50 m terrain tile 50 km from the world origin (georeferenced: read in a local
// frame; the mesh is written back in world coordinates, which read_mesh takes below 1e6 m),
// heights around 300 m.
std::vector<Eigen::Vector3d> utm_terrain() {
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 125; ++i)
    for (int j = 0; j < 125; ++j) {
      const double x = 0.4 * i, y = 0.4 * j;
      points.emplace_back(52000.0 + x, 43000.0 + y,
                          300.0 + 2.0 * std::sin(0.25 * x) * std::cos(0.2 * y));
    }
  return points;
}

// Share of the mesh's triangles (by count) whose normal has a positive dot product with
// `direction(centroid)`.
template <typename Direction>
double share_of_faces(const TriangleMesh& mesh, Direction direction) {
  std::size_t agree = 0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3f a = mesh.vertices[t[0]], b = mesh.vertices[t[1]], c = mesh.vertices[t[2]];
    const Eigen::Vector3f n = (b - a).cross(c - a);
    agree += n.dot(direction((a + b + c) / 3.0f)) > 0.0f ? 1 : 0;
  }
  return mesh.triangles.empty()
             ? 0.0
             : static_cast<double>(agree) / static_cast<double>(mesh.triangles.size());
}

double share_up(const TriangleMesh& mesh) {
  return share_of_faces(mesh, [](const Eigen::Vector3f&) { return Eigen::Vector3f::UnitZ(); });
}

TEST(CliOrientation, AnAerialLasTileFacesUpWithoutAFlag) {
  const std::string dir = test::temp_dir();
  test::write_file(dir + "/tile.las", las_file_of(utm_terrain()));
  const test::CliRun run =
      test::run_cli("reconstruct " + dir + "/tile.las -o " + dir + "/tile.ply --voxel 1");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("up (LAS or map coordinates: heights along z)"), std::string::npos)
      << run.out;
  const TriangleMesh mesh = io::read_mesh(dir + "/tile.ply");
  ASSERT_GT(mesh.triangles.size(), 1000u);
  EXPECT_GE(share_up(mesh), 0.99);
}

// The same tile as ASCII XYZ in map coordinates (a terrain tile as mapping agencies hand it out):
// a local frame, heights along z, faces up without a flag.
TEST(CliOrientation, AnXyzTerrainTileInMapCoordinatesFacesUp) {
  const std::string dir = test::temp_dir();
  std::string text;
  char line[96];
  for (const Eigen::Vector3d& p : utm_terrain()) {
    std::snprintf(line, sizeof line, "%.3f %.3f %.3f\n", p.x(), p.y(), p.z());
    text += line;
  }
  test::write_file(dir + "/tile.xyz", text);
  const test::CliRun run =
      test::run_cli("reconstruct " + dir + "/tile.xyz -o " + dir + "/tile.ply --voxel 1");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("heights along z"), std::string::npos) << run.out;
  const TriangleMesh mesh = io::read_mesh(dir + "/tile.ply");
  ASSERT_GT(mesh.triangles.size(), 1000u);
  EXPECT_GE(share_up(mesh), 0.98);                 // (98.9 % measured)
  EXPECT_GT(mesh.vertices.front().x(), 51000.0f);  // written back in world coordinates
  // --crop is in the file's own (world) coordinates too: the western half.
  const test::CliRun cropped =
      test::run_cli("reconstruct " + dir + "/tile.xyz -o " + dir +
                    "/west.ply --voxel 1 --crop 51990,42990,0,52025,43060,1000");
  ASSERT_EQ(cropped.exit_code, 0) << cropped.err;
  const TriangleMesh west = io::read_mesh(dir + "/west.ply");
  ASSERT_GT(west.triangles.size(), 200u);
  for (const Eigen::Vector3f& v : west.vertices) ASSERT_LT(v.x(), 52027.0f);
}

// The same hills in local coordinates (no map offset, no LAS flag: nothing in the file says
// which way is up), around a valley, so outward from the centroid would face down: up, because
// the points form one surface over x-y, and the report says so.
TEST(CliOrientation, AnXyzTerrainTileInLocalCoordinatesFacesUp) {
  const std::string dir = test::temp_dir();
  std::string text;
  char line[96];
  for (const Eigen::Vector3d& p : utm_terrain()) {
    const double x = p.x() - 52025.0, y = p.y() - 43025.0;
    std::snprintf(line, sizeof line, "%.3f %.3f %.3f\n", x, y,
                  p.z() - 300.0 + 0.01 * (x * x + y * y));
    text += line;
  }
  test::write_file(dir + "/tile.xyz", text);
  const test::CliRun run =
      test::run_cli("reconstruct " + dir + "/tile.xyz -o " + dir + "/tile.ply --voxel 1");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("one surface over x-y"), std::string::npos) << run.out;
  const TriangleMesh mesh = io::read_mesh(dir + "/tile.ply");
  ASSERT_GT(mesh.triangles.size(), 1000u);
  EXPECT_GE(share_up(mesh), 0.98);
  const test::CliRun info = test::run_cli("info " + dir + "/tile.xyz");
  EXPECT_NE(info.out.find("one surface over x-y"), std::string::npos) << info.out;
  // Out of core: a chunk cannot tell a terrain by itself; the first batch decides for all.
  const test::CliRun chunked = test::run_cli("reconstruct " + dir + "/tile.xyz -o " + dir +
                                             "/chunked.ply --voxel 1 --chunk 20");
  ASSERT_EQ(chunked.exit_code, 0) << chunked.err;
  const TriangleMesh chunked_mesh = io::read_mesh(dir + "/chunked.ply");
  ASSERT_GT(chunked_mesh.triangles.size(), 1000u);
  EXPECT_GE(share_up(chunked_mesh), 0.98);
}

TEST(CliOrientation, UpDownFlipAndViewpointsInWorldCoordinates) {
  const std::string dir = test::temp_dir();
  test::write_file(dir + "/tile.las", las_file_of(utm_terrain()));
  const auto faces_up = [&](const std::string& orient) {
    const test::CliRun run = test::run_cli("reconstruct " + dir + "/tile.las -o " + dir +
                                           "/t.ply --voxel 1 --orient " + orient);
    EXPECT_EQ(run.exit_code, 0) << orient << ": " << run.err;
    return share_up(io::read_mesh(dir + "/t.ply"));
  };
  EXPECT_LE(faces_up("down"), 0.01);
  EXPECT_GE(faces_up("up"), 0.99);
  EXPECT_LE(faces_up("flip"), 0.01);
  // World coordinates of the file: above and below the tile.
  EXPECT_GE(faces_up("viewpoint=52025,43025,1000"), 0.99);
  EXPECT_LE(faces_up("viewpoint=52025,43025,-1000"), 0.01);
  EXPECT_EQ(test::run_cli("reconstruct " + dir + "/tile.las -o " + dir + "/t.ply --orient sideways")
                .exit_code,
            2);
}

// The Kinect mug as Open3D's remove_non_finite_points + write_point_cloud leave it: the
// camera-frame points without the invalid pixels, with their colours, no VIEWPOINT, unorganized.
TEST(CliOrientation, ACameraFrameCloudWrittenByOpen3dFacesTheCamera) {
  if (!test::has_data("kinect_pcl/table_scene_mug_stereo_textured.pcd"))
    GTEST_SKIP() << "needs $MESHFLOW_DATA/kinect_pcl (the shared data)";
  const PointCloud organized =
      io::read_point_cloud(test::data_path("kinect_pcl/table_scene_mug_stereo_textured.pcd"));
  std::vector<std::uint32_t> finite;
  for (std::size_t i = 0; i < organized.size(); ++i)
    if (organized.positions[i].allFinite()) finite.push_back(static_cast<std::uint32_t>(i));
  PointCloud cloud = select_points(organized, finite);
  ASSERT_TRUE(cloud.sensor_origin.isZero());  // the PCD's viewpoint is the camera
  cloud.has_sensor_origin = false;
  const std::string dir = test::temp_dir();
  io::PlyPointWriter writer(dir + "/mug.ply", cloud.size(), false, cloud.has_colors());
  writer.append(cloud);
  writer.finish();
  const test::CliRun run = test::run_cli("reconstruct " + dir + "/mug.ply -o " + dir + "/m.ply");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("facing the origin (one camera view"), std::string::npos) << run.out;
  const TriangleMesh mesh = io::read_mesh(dir + "/m.ply");
  ASSERT_GT(mesh.triangles.size(), 1000u);
  EXPECT_GE(share_of_faces(mesh, [](const Eigen::Vector3f& c) { return Eigen::Vector3f(-c); }),
            0.9);
}

// meshflow's own closed objects, sampled without normals: outward, and the report says so.
TEST(CliOrientation, ClosedObjectsFaceOutward) {
  const std::string dir = test::temp_dir();
  for (const char* object : {"sphere", "torus", "chamfered-cube"}) {
    ASSERT_EQ(
        test::run_cli(std::string("sample ") + object + " -o " + dir + "/o.ply --points 20000")
            .exit_code,
        0);
    const test::CliRun run =
        test::run_cli("reconstruct " + dir + "/o.ply -o " + dir + "/o_mesh.ply");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_NE(run.out.find("outward (a closed object"), std::string::npos) << run.out;
    // Outward winding: a positive enclosed volume (the torus's inner ring faces its centre).
    const TriangleMesh mesh = io::read_mesh(dir + "/o_mesh.ply");
    double six_volume = 0.0;
    for (const auto& t : mesh.triangles)
      six_volume += static_cast<double>(
          mesh.vertices[t[0]].dot(mesh.vertices[t[1]].cross(mesh.vertices[t[2]])));
    EXPECT_GT(six_volume, 0.0) << object;
  }
}

}  // namespace
}  // namespace meshflow
