// `meshflow info MESH` (issue 55 item 9): statistics of meshflow's reconstructions of its own
// closed objects against their analytic area, volume and genus; an open grid's border; a
// point-cloud PLY still reported as a cloud. And the per-vertex quality of reconstruct
// --quality against a brute-force nearest-point search.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli_runner.h"
#include "nodes/io/read_point_cloud.h"
#include "nodes/synthetic/closed_objects.h"

namespace meshflow {
namespace {

constexpr double kPi = 3.14159265358979323846;

nlohmann::json info_json(const std::string& path) {
  return test::json_of(test::run_cli("info " + path + " --json"));
}

TEST(CliInfo, ReconstructedObjectsHaveTheirAnalyticAreaVolumeAndGenus) {
  const std::string dir = test::temp_dir();
  const struct {
    const char* name;
    double volume;
    int genus;
    const char* format;
  } objects[] = {{"sphere", 4.0 / 3.0 * kPi * 0.125, 0, ".ply"},
                 {"torus", 2 * kPi * kPi * 0.4 * 0.15 * 0.15, 1, ".glb"},
                 {"box", 0.8 * 0.6 * 0.5, 0, ".obj"}};
  for (const auto& o : objects) {
    SCOPED_TRACE(o.name);
    const std::string mesh = dir + "/" + o.name + o.format;
    ASSERT_EQ(
        test::run_cli(std::string("sample ") + o.name + " -o " + dir + "/p.ply --points " + "40000")
            .exit_code,
        0);
    const test::CliRun rec = test::run_cli("reconstruct " + dir + "/p.ply -o " + mesh + " -q");
    ASSERT_EQ(rec.exit_code, 0) << rec.err;
    const nlohmann::json doc = info_json(mesh);
    ASSERT_TRUE(doc.contains("area_m2")) << doc.dump();
    const double area = synthetic::closed_test_object(o.name)->area();
    EXPECT_NEAR(doc["area_m2"].get<double>(), area, 0.03 * area);
    ASSERT_TRUE(doc["closed"].get<bool>()) << doc.dump();
    EXPECT_NEAR(doc["volume_m3"].get<double>(), o.volume, 0.03 * o.volume);
    EXPECT_EQ(doc["orientation"], "outward");
    EXPECT_EQ(doc["genus"], o.genus);
    EXPECT_EQ(doc["euler_characteristic"], 2 - 2 * o.genus);
    EXPECT_EQ(doc["components"], 1);
    EXPECT_EQ(doc["border_loops"], 0);
    EXPECT_EQ(doc["non_manifold_edges"], 0);
    EXPECT_EQ(doc["non_manifold_vertices"], 0);
    const Eigen::AlignedBox3f box = synthetic::closed_test_object(o.name)->bounds;
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(doc["bounds"]["min"][k].get<double>(), box.min()[k], 0.02);
      EXPECT_NEAR(doc["bounds"]["max"][k].get<double>(), box.max()[k], 0.02);
    }
  }
  // The report in words names the same figures.
  const test::CliRun run = test::run_cli("info " + dir + "/torus.glb");
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("genus 1"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("closed, faces outward"), std::string::npos) << run.out;
}

TEST(CliInfo, OpenGridHasOneBorderLoopAndNoVolume) {
  const std::string dir = test::temp_dir();
  std::string obj;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) obj += "v " + std::to_string(i) + " " + std::to_string(j) + " 0\n";
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      const int a = j * 4 + i + 1;
      obj += "f " + std::to_string(a) + " " + std::to_string(a + 1) + " " + std::to_string(a + 5) +
             " " + std::to_string(a + 4) + "\n";
    }
  test::write_file(dir + "/grid.obj", obj);
  const nlohmann::json doc = info_json(dir + "/grid.obj");
  EXPECT_EQ(doc["triangles"], 18);
  EXPECT_DOUBLE_EQ(doc["area_m2"].get<double>(), 9.0);
  EXPECT_EQ(doc["border_loops"], 1);
  EXPECT_EQ(doc["border_edges"], 12);
  EXPECT_FALSE(doc["closed"].get<bool>());
  EXPECT_TRUE(doc["volume_m3"].is_null());
  EXPECT_EQ(doc["genus"], 0);
  EXPECT_EQ(doc["euler_characteristic"], 1);
  EXPECT_EQ(doc["degenerate_triangles"], 0);
}

TEST(CliInfo, PlyWithoutFacesIsStillACloud) {
  const std::string dir = test::temp_dir();
  ASSERT_EQ(test::run_cli("sample sphere -o " + dir + "/p.ply --points 1000").exit_code, 0);
  const nlohmann::json doc = info_json(dir + "/p.ply");
  EXPECT_EQ(doc["points"], 1000);
  EXPECT_FALSE(doc.contains("triangles"));
}

}  // namespace
}  // namespace meshflow

namespace meshflow {
namespace {

// The float vertex property `property` of a binary PLY written by meshflow, with the positions.
void read_vertex_scalar(const std::string& path, const std::string& property,
                        std::vector<Eigen::Vector3f>& positions, std::vector<float>& values) {
  const std::string bytes = test::read_file(path);
  const std::size_t end = bytes.find("end_header\n");
  ASSERT_NE(end, std::string::npos);
  std::istringstream header(bytes.substr(0, end));
  std::string line;
  std::size_t count = 0, stride = 0, x_at = 0, quality_at = 0;
  bool in_vertex = false, has_quality = false;
  while (std::getline(header, line)) {
    std::istringstream words(line);
    std::string word, type, name;
    words >> word;
    if (word == "element") {
      words >> name;
      in_vertex = name == "vertex";
      if (in_vertex) words >> count;
    } else if (word == "property" && in_vertex) {
      words >> type >> name;
      if (name == "x") x_at = stride;
      if (name == property) quality_at = stride, has_quality = true;
      ASSERT_TRUE(type == "float" || type == "uchar") << line;
      stride += type == "float" ? 4 : 1;
    }
  }
  ASSERT_TRUE(has_quality) << bytes.substr(0, end);
  const char* data = bytes.data() + end + 11;
  for (std::size_t i = 0; i < count; ++i) {
    Eigen::Vector3f p;
    float q;
    std::memcpy(p.data(), data + i * stride + x_at, 12);
    std::memcpy(&q, data + i * stride + quality_at, 4);
    positions.push_back(p);
    values.push_back(q);
  }
}

// reconstruct --quality: each vertex's `quality` is its distance to the nearest input point,
// as a brute-force search over the input finds it.
TEST(CliQuality, VertexQualityIsTheDistanceToTheNearestInputPoint) {
  const std::string dir = test::temp_dir();
  ASSERT_EQ(test::run_cli("sample sphere -o " + dir + "/s.ply --points 5000").exit_code, 0);
  const test::CliRun run =
      test::run_cli("reconstruct " + dir + "/s.ply -o " + dir + "/m.ply --quality --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json doc = nlohmann::json::parse(run.out);
  std::vector<Eigen::Vector3f> vertices;
  std::vector<float> quality;
  read_vertex_scalar(dir + "/m.ply", "quality", vertices, quality);
  ASSERT_GT(vertices.size(), 100u);
  const PointCloud input = io::read_point_cloud(dir + "/s.ply");
  float max = 0.0f;
  for (std::size_t i = 0; i < vertices.size(); i += 7) {
    float best = std::numeric_limits<float>::infinity();
    for (const Eigen::Vector3f& p : input.positions)
      best = std::min(best, (p - vertices[i]).norm());
    EXPECT_NEAR(quality[i], best, 1e-6f) << i;
  }
  for (float q : quality) max = std::max(max, q);
  EXPECT_NEAR(doc["quality"]["max"].get<double>(), max, 1e-6);
  EXPECT_LT(doc["quality"]["p95"].get<double>(), doc["voxel"].get<double>()) << "near the data";
  EXPECT_LT(max, doc["voxel"].get<double>() * 3);
  // `observations`: the input points within one voxel of each vertex, as brute force counts.
  std::vector<Eigen::Vector3f> same;
  std::vector<float> observations;
  read_vertex_scalar(dir + "/m.ply", "observations", same, observations);
  ASSERT_EQ(same, vertices);
  const float voxel = doc["voxel"].get<float>();
  for (std::size_t i = 0; i < vertices.size(); i += 7) {
    std::size_t within = 0;
    for (const Eigen::Vector3f& p : input.positions) within += (p - vertices[i]).norm() <= voxel;
    EXPECT_NEAR(observations[i], static_cast<float>(within), 1.0f) << i;  // rounding at r
  }
  // 5 000 points on a sphere at the automatic voxel: a handful per vertex, a few vertices (those
  // over a voxel from the nearest point, where `quality` is largest) with none.
  EXPECT_GE(doc["observations"]["median"].get<double>(), 3.0);
  EXPECT_GE(doc["observations"]["p5"].get<double>(), 1.0);
  EXPECT_EQ(doc["observations"]["min"].get<double>() == 0.0, max > voxel);
  // Other formats have no place for it: a clear error before any work.
  const test::CliRun obj =
      test::run_cli("reconstruct " + dir + "/s.ply -o " + dir + "/m.obj --quality");
  EXPECT_EQ(obj.exit_code, 1);
  EXPECT_NE(obj.err.find("--quality writes a PLY vertex property"), std::string::npos) << obj.err;
}

// run --fuse --quality: fused.ply's `observations` are the map's weight at each vertex, the
// frames that saw it (constant weighting): between 0 and the number of frames, most surface
// seen by several.
TEST(CliQuality, FusedMapObservationsCountTheFramesThatSawEachVertex) {
  const std::string dir = test::temp_dir();
  const test::CliRun run = test::run_cli(
      "run --synthetic-depth --synthetic-frames 12 --synthetic-size 160x120 --fuse -o " + dir +
      "/out --quality --voxel 0.04 --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json doc = nlohmann::json::parse(run.out);
  std::vector<Eigen::Vector3f> vertices;
  std::vector<float> observations;
  read_vertex_scalar(dir + "/out/fused.ply", "observations", vertices, observations);
  ASSERT_GT(vertices.size(), 1000u);
  for (float w : observations) {
    ASSERT_GE(w, 0.0f);
    ASSERT_LE(w, 12.0f + 1e-4f);
  }
  EXPECT_GE(doc["observations"]["median"].get<double>(), 2.0);
  EXPECT_EQ(doc["observations"]["vertices"].get<std::size_t>(), vertices.size());
}

}  // namespace
}  // namespace meshflow
