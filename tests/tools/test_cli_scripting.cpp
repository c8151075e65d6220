// The CLI as scripts use it: --version, -q / -v, --json documents, every mesh format, optimize
// on meshes from other tools, shared Kinect data with colours.

#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "nodes/io/mesh_readers.h"
#include "test_support.h"
#include "tools/cli_runner.h"

namespace meshflow {
namespace {

using test::CliRun;
using test::run_cli;

nlohmann::json parse_json(const CliRun& r) {
  EXPECT_EQ(r.exit_code, 0) << r.err;
  try {
    return nlohmann::json::parse(r.out);
  } catch (const nlohmann::json::exception& e) {
    ADD_FAILURE() << e.what() << "\n" << r.out;
    return {};
  }
}

// A 20 000-point torus sample, written once per test.
std::string torus_cloud(const std::string& dir) {
  const std::string path = dir + "/torus.ply";
  const CliRun r = run_cli("sample torus --points 20000 -q -o " + path);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "") << "-q prints nothing";
  return path;
}

TEST(CliScripting, VersionAndDefaultsInHelp) {
  CliRun r = run_cli("--version");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.out.rfind("meshflow ", 0), 0u) << r.out;
  r = run_cli("reconstruct --help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("=10"), std::string::npos) << "--kn shows its default\n" << r.out;
  EXPECT_NE(r.out.find("=auto"), std::string::npos) << "--extract shows its default";
  EXPECT_EQ(run_cli("reconstruct a.ply -o b.ply -q -v").exit_code, 2) << "-q excludes -v";
}

// The line of `help` that shows `option`.
std::string help_line(const std::string& help, const std::string& option) {
  const std::size_t at = help.find("  " + option + " ");
  if (at == std::string::npos) return "";
  return help.substr(at, help.find('\n', at) - at);
}

// Issue 55: defaults that are sentinels show what they mean, --max-memory shows its default,
// optimize lists only the options it uses.
TEST(CliScripting, HelpShowsWhatSentinelDefaultsMean) {
  const CliRun r = run_cli("reconstruct --help");
  ASSERT_EQ(r.exit_code, 0);
  for (const char* option :
       {"--voxel", "--contour-tolerance", "--remesh-tolerance", "--threads", "--max-memory"}) {
    const std::string line = help_line(r.out, option);
    ASSERT_NE(line, "") << option << "\n" << r.out;
    EXPECT_EQ(line.find("=-1"), std::string::npos) << line;
    EXPECT_EQ(line.find("=0 "), std::string::npos) << line;
  }
  EXPECT_NE(help_line(r.out, "--voxel").find("=auto"), std::string::npos) << r.out;
  EXPECT_NE(help_line(r.out, "--contour-tolerance").find("=auto"), std::string::npos) << r.out;
  EXPECT_NE(help_line(r.out, "--max-memory").find("=80% of RAM"), std::string::npos) << r.out;
  const CliRun d = run_cli("decompress --help");
  ASSERT_EQ(d.exit_code, 0);
  EXPECT_EQ(d.out.find("=-1"), std::string::npos) << d.out;
  EXPECT_NE(help_line(d.out, "--level").find("=all"), std::string::npos) << d.out;
  const CliRun o = run_cli("optimize --help");
  ASSERT_EQ(o.exit_code, 0);
  for (const char* unused : {"--depth-median", "--depth-bilateral", "--max-rim", "--max-memory"})
    EXPECT_EQ(o.out.find(unused), std::string::npos) << unused << "\n" << o.out;
  EXPECT_NE(help_line(o.out, "--voxel").find("=auto"), std::string::npos) << o.out;
  EXPECT_EQ(run_cli("optimize a.ply b.ply --depth-median 3").exit_code, 2);
}

// An option's name appears once in its error, and the bad-extension error lists .mfc where
// reconstruct accepts it.
TEST(CliScripting, UsageErrorsNameTheOptionOnce) {
  CliRun r = run_cli("reconstruct a.ply -o b.ply --optimize clean,foo");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--optimize: step 'foo': expected"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("--optimize: --optimize"), std::string::npos) << r.err;
  r = run_cli("reconstruct a.ply -o b.ply --orient sideways");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--orient: expected auto"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("--orient: --orient"), std::string::npos) << r.err;
  const std::string dir = test::temp_dir();
  r = run_cli("reconstruct " + torus_cloud(dir) + " -o " + dir + "/m.vrml");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("unknown mesh format '.vrml'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(".mfc"), std::string::npos) << r.err;
}

TEST(CliScripting, JsonDocumentsOfInfoReconstructAndEval) {
  const std::string dir = test::temp_dir();
  const std::string cloud = torus_cloud(dir);
  nlohmann::json doc = parse_json(run_cli("info --json " + cloud));
  EXPECT_EQ(doc["points"], 20000);
  EXPECT_EQ(doc["normals"]["orientation"], "propagate");
  EXPECT_EQ(doc["bounds"]["min"].size(), 3u);

  doc = parse_json(run_cli("reconstruct " + cloud + " -o " + dir + "/m.glb --voxel 0.02 --json"));
  EXPECT_EQ(doc["points"], 20000);
  EXPECT_EQ(doc["normals"]["source"], "estimate");
  EXPECT_GT(doc["mesh"]["triangles"].get<int>(), 1000);
  EXPECT_EQ(doc["output"], dir + "/m.glb");
  EXPECT_FALSE(doc["stages"].empty());
  EXPECT_EQ(doc["optimize"][0]["step"], "clean");
  EXPECT_TRUE(std::filesystem::exists(dir + "/m.glb"));

  ASSERT_EQ(run_cli("reconstruct " + cloud + " -o " + dir + "/m.stl --voxel 0.02 -q").exit_code, 0);
  doc = parse_json(run_cli("eval " + dir + "/m.stl --object torus --json"));
  EXPECT_TRUE(doc["topology"]["watertight"].get<bool>());
  EXPECT_EQ(doc["orientation"], "outward");
  EXPECT_LT(doc["relative_to_diagonal"]["surface_mean"].get<double>(), 2e-4);

  // An inside-out copy: eval says so, against the exact object and against the outward mesh.
  TriangleMesh mesh = io::read_mesh(dir + "/m.stl");
  ASSERT_EQ(run_cli("reconstruct " + cloud + " -o " + dir + "/m.off --voxel 0.02 -q").exit_code, 0);
  std::string off = test::read_file(dir + "/m.off");
  test::write_file(dir + "/flipped.obj", [&] {
    std::string obj;
    for (const Eigen::Vector3f& v : mesh.vertices)
      obj += "v " + std::to_string(v.x()) + " " + std::to_string(v.y()) + " " +
             std::to_string(v.z()) + "\n";
    for (const Triangle& t : mesh.triangles)
      obj += "f " + std::to_string(t[0] + 1) + " " + std::to_string(t[2] + 1) + " " +
             std::to_string(t[1] + 1) + "\n";
    return obj;
  }());
  doc = parse_json(run_cli("eval " + dir + "/flipped.obj --object torus --json"));
  EXPECT_EQ(doc["orientation"], "inside out");
  doc = parse_json(run_cli("eval " + dir + "/flipped.obj --reference " + dir + "/m.off --json"));
  EXPECT_GT(doc["inside_out_area_share"].get<double>(), 0.99);
  doc = parse_json(run_cli("eval " + dir + "/m.stl --reference " + dir + "/m.off --json"));
  EXPECT_LT(doc["inside_out_area_share"].get<double>(), 0.01);
  EXPECT_LT(doc["mesh_to_reference"]["max"].get<double>(), 1e-6) << "the same mesh";
}

TEST(CliScripting, JsonOfRunAndProfileAndVerboseFrameLines) {
  const std::string dir = test::temp_dir();
  nlohmann::json doc =
      parse_json(run_cli("run --synthetic --max-frames 2 --voxel 0.1 --json -o " + dir + "/run"));
  EXPECT_EQ(doc["frames_ok"], 2);
  EXPECT_EQ(doc["frames_failed"], 0);
  EXPECT_EQ(doc["files_written"], 2);
  EXPECT_GT(doc["frames_per_second"].get<double>(), 0.0);
  doc = parse_json(
      run_cli("profile --synthetic --max-frames 2 --voxel 0.1 --json --csv " + dir + "/s.csv"));
  EXPECT_EQ(doc["csv"], dir + "/s.csv");
  EXPECT_FALSE(doc["stages"].empty());
  const CliRun r = run_cli("run --synthetic --max-frames 2 --voxel 0.1 -v -o " + dir + "/v");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("frame 1 "), std::string::npos) << r.out;
  const CliRun q = run_cli("run --synthetic --max-frames 2 --voxel 0.1 -q -o " + dir + "/q");
  EXPECT_EQ(q.exit_code, 0);
  EXPECT_EQ(q.out, "");
  EXPECT_EQ(q.err, "") << "no progress lines without a terminal";
  const CliRun p =
      run_cli("run --synthetic --max-frames 2 --voxel 0.1 -q --progress -o " + dir + "/p");
  EXPECT_NE(p.err.find("2/2 frames"), std::string::npos) << p.err;
}

// A depth camera circling an object, written as a TUM RGB-D directory by `sample --orbit`, fused
// by `run --fuse`: the completeness breakdown in --json and the per-frame lines with -v.
TEST(CliScripting, FusedOrbitReportsWhereTheSurfaceGoes) {
  const std::string dir = test::temp_dir();
  ASSERT_EQ(run_cli("sample torus --orbit 6 --size 160x120 -q -o " + dir + "/orbit").exit_code, 0);
  nlohmann::json doc =
      parse_json(run_cli("run " + dir + "/orbit --fuse --voxel 0.02 --json -o " + dir + "/fused"));
  EXPECT_EQ(doc["frames_ok"], 6);
  const nlohmann::json& c = doc["completeness"];
  EXPECT_EQ(c["pixels"]["total"], 6 * 160 * 120);
  EXPECT_GT(c["pixels"]["fused"].get<std::size_t>(), 6000u);
  EXPECT_EQ(c["pixels"]["occlusion_edges"], 0) << "fusion keeps silhouette pixels";
  EXPECT_EQ(c["pixels"]["moved_by_smoothing"], 0);
  EXPECT_GT(c["voxels_observed"].get<std::size_t>(), 0u);
  EXPECT_GT(c["cells_meshed"].get<std::size_t>(), 1000u);
  EXPECT_LT(c["cells_left_out"].get<std::size_t>(), c["cells_meshed"].get<std::size_t>() / 20);
  EXPECT_GT(doc["mesh"]["triangles"].get<std::size_t>(), 1000u);
  const CliRun v =
      run_cli("run " + dir + "/orbit --fuse --voxel 0.02 --min-weight 1 -v -o " + dir + "/v");
  EXPECT_EQ(v.exit_code, 0) << v.err;
  EXPECT_NE(v.out.find("pixels fused ("), std::string::npos) << v.out;
  EXPECT_NE(v.out.find("at or below --min-weight"), std::string::npos) << v.out;
  EXPECT_EQ(run_cli("run " + dir + "/orbit --fuse --behind 0 -o " + dir + "/b").exit_code, 2);
  // Smoothing moves depths but drops no pixel.
  const nlohmann::json smoothed = parse_json(run_cli(
      "run " + dir + "/orbit --fuse --voxel 0.02 --depth-median 5 --json -o " + dir + "/m"));
  EXPECT_GT(smoothed["completeness"]["pixels"]["moved_by_smoothing"].get<std::size_t>(), 100u);
  EXPECT_EQ(smoothed["completeness"]["pixels"]["fused"], c["pixels"]["fused"]);
  EXPECT_EQ(run_cli("run " + dir + "/orbit --fuse --depth-median 4 -o " + dir + "/x").exit_code, 2);
  // The along-ray integrator: a mesh about as large, from fewer observed voxels.
  nlohmann::json along = parse_json(run_cli("run " + dir +
                                            "/orbit --fuse --voxel 0.02 --integrator along-ray "
                                            "--json -o " +
                                            dir + "/along"));
  EXPECT_EQ(along["frames_ok"], 6);
  EXPECT_GT(along["mesh"]["triangles"].get<std::size_t>(),
            doc["mesh"]["triangles"].get<std::size_t>() * 8 / 10);
  EXPECT_LT(along["completeness"]["voxels_observed"].get<std::size_t>(),
            c["voxels_observed"].get<std::size_t>());
  EXPECT_EQ(run_cli("run " + dir + "/orbit --fuse --integrator raycast -o " + dir + "/r").exit_code,
            2);
  // Carving is counted, and --no-carve turns it off.
  EXPECT_TRUE(c["blocks_carved"].is_number_unsigned());
  const nlohmann::json kept = parse_json(
      run_cli("run " + dir + "/orbit --fuse --voxel 0.02 --no-carve --json -o " + dir + "/k"));
  EXPECT_EQ(kept["completeness"]["blocks_carved"], 0);
  EXPECT_EQ(run_cli("run " + dir + "/orbit --no-carve -o " + dir + "/n").exit_code, 2)
      << "--no-carve needs --fuse";
}

TEST(CliScripting, OptimizeAMeshFromAnotherTool) {
  const std::string dir = test::temp_dir();
  const std::string cloud = torus_cloud(dir);
  ASSERT_EQ(run_cli("reconstruct " + cloud + " -o " + dir + "/m.obj --voxel 0.02 -q").exit_code, 0);
  const nlohmann::json doc = parse_json(
      run_cli("optimize " + dir + "/m.obj " + dir + "/d.ply --optimize decimate --json"));
  EXPECT_EQ(doc["optimize"][0]["step"], "decimate");
  const auto in = doc["triangles_in"].get<double>(), out = doc["triangles"].get<double>();
  EXPECT_NEAR(out / in, 0.25, 0.02);
  EXPECT_EQ(io::read_mesh(dir + "/d.ply").triangles.size(), static_cast<std::size_t>(out));
  EXPECT_EQ(run_cli("optimize " + dir + "/m.obj " + dir + "/d.vrml").exit_code, 1);
  // The output also as -o / --output, as reconstruct takes it.
  ASSERT_EQ(run_cli("optimize " + dir + "/m.obj -o " + dir + "/o.ply -q").exit_code, 0);
  EXPECT_TRUE(std::filesystem::exists(dir + "/o.ply"));
  ASSERT_EQ(run_cli("optimize --output " + dir + "/o.obj " + dir + "/m.obj -q").exit_code, 0);
  EXPECT_TRUE(std::filesystem::exists(dir + "/o.obj"));
  EXPECT_EQ(run_cli("optimize " + dir + "/m.obj " + dir + "/x.ply -o " + dir + "/y.ply").exit_code,
            2)
      << "two outputs";
  EXPECT_EQ(run_cli("optimize " + dir + "/m.obj " + dir + "/d.ply --kn 5").exit_code, 2)
      << "only the optimize settings are options here";
}

TEST(CliScripting, CompressDecompressAndInfoOfAMesh) {
  const std::string dir = test::temp_dir();
  const std::string cloud = torus_cloud(dir);
  ASSERT_EQ(run_cli("reconstruct " + cloud + " -o " + dir + "/m.ply --voxel 0.02 -q").exit_code, 0);
  const TriangleMesh input = io::read_mesh(dir + "/m.ply");
  nlohmann::json doc = parse_json(run_cli("compress " + dir + "/m.ply " + dir + "/m.mfc --json"));
  EXPECT_EQ(doc["kind"], "edgebreaker");
  EXPECT_LT(doc["connectivity_bits_per_triangle"].get<double>(), 2.5);
  EXPECT_EQ(doc["bytes"].get<std::size_t>(), std::filesystem::file_size(dir + "/m.mfc"));
  doc = parse_json(run_cli("info --json " + dir + "/m.mfc"));
  EXPECT_EQ(doc["triangles"].get<std::size_t>(), input.triangles.size());
  doc = parse_json(run_cli("decompress " + dir + "/m.mfc " + dir + "/d.ply --json"));
  EXPECT_EQ(io::read_mesh(dir + "/d.ply").triangles.size(), input.triangles.size());
  doc = parse_json(run_cli("compress " + dir + "/m.ply " + dir + "/p.mfc --progressive --json"));
  EXPECT_EQ(doc["kind"], "progressive");
  const auto base = doc["base_triangles"].get<std::size_t>();
  doc = parse_json(run_cli("decompress " + dir + "/p.mfc " + dir + "/b.obj --level 0 --json"));
  EXPECT_EQ(doc["triangles"].get<std::size_t>(), base);
  doc = parse_json(run_cli("decompress " + dir + "/p.mfc " + dir + "/h.ply --triangles " +
                           std::to_string(input.triangles.size() / 2) + " --json"));
  EXPECT_NEAR(doc["triangles"].get<double>(), static_cast<double>(input.triangles.size()) / 2, 4);
  // From the graph's compress stage: reconstruct to a .mfc, run --compress per frame.
  doc = parse_json(run_cli("reconstruct " + cloud + " -o " + dir + "/r.mfc --voxel 0.02 --json"));
  EXPECT_GT(doc["compressed_bytes"].get<std::size_t>(), 1000u);
  EXPECT_EQ(parse_json(run_cli("info --json " + dir + "/r.mfc"))["kind"], "edgebreaker");
  EXPECT_EQ(
      run_cli("reconstruct " + cloud + " -o " + dir + "/r.ply --compress progressive").exit_code, 1)
      << "--compress needs a .mfc output";
  ASSERT_EQ(run_cli("sample sphere --orbit 3 --size 160x120 -q -o " + dir + "/orbit").exit_code, 0);
  doc = parse_json(run_cli("run " + dir + "/orbit --voxel 0.02 --compress progressive --json -o " +
                           dir + "/frames"));
  EXPECT_EQ(doc["frames_ok"], 3);
  EXPECT_EQ(parse_json(run_cli("info --json " + dir + "/frames/frame_000000.mfc"))["kind"],
            "progressive");
  // The profiler times the compress stage like any other.
  const CliRun profile =
      run_cli("profile " + dir + "/orbit --voxel 0.02 --compress edgebreaker --csv " + dir +
              "/stages.csv -q");
  EXPECT_EQ(profile.exit_code, 0) << profile.err;
  EXPECT_NE(test::read_file(dir + "/stages.csv").find("compress"), std::string::npos);
  // The output also as -o / --output.
  ASSERT_EQ(run_cli("compress " + dir + "/m.ply -o " + dir + "/o.mfc -q").exit_code, 0);
  ASSERT_EQ(run_cli("decompress " + dir + "/o.mfc --output " + dir + "/o.ply -q").exit_code, 0);
  EXPECT_EQ(io::read_mesh(dir + "/o.ply").triangles.size(), input.triangles.size());
  test::write_file(dir + "/bad.mfc", "MFMESH\r\n garbage");
  const CliRun bad = run_cli("decompress " + dir + "/bad.mfc " + dir + "/x.ply");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("bad.mfc"), std::string::npos) << bad.err;
}

TEST(CliScripting, ColumnsOfATextCloud) {
  const std::string path = test::temp_dir() + "/n.txt";
  test::write_file(path, "1 2 3 0 0 1\n4 5 6 0 1 0\n7 8 9 1 0 0\n");
  nlohmann::json doc = parse_json(run_cli("info --json " + path));
  EXPECT_TRUE(doc["fields"]["colors"].get<bool>()) << "integers: detected as colours";
  doc = parse_json(run_cli("info --json --columns x,y,z,nx,ny,nz " + path));
  EXPECT_TRUE(doc["fields"]["normals"].get<bool>());
  EXPECT_FALSE(doc["fields"]["colors"].get<bool>());
  EXPECT_EQ(run_cli("info --columns x,y,q " + path).exit_code, 1);
}

TEST(CliScripting, ErrorsSayWhy) {
  const CliRun r = run_cli("reconstruct /nonexistent/cloud.ply -o x.ply");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("No such file or directory"), std::string::npos) << r.err;
  const std::string dir = test::temp_dir();
  const std::string cloud = torus_cloud(dir);
  const CliRun w = run_cli("reconstruct " + cloud + " -o /nonexistent/m.ply --voxel 0.05");
  EXPECT_EQ(w.exit_code, 1);
  EXPECT_NE(w.err.find("cannot create output file: No such file or directory"), std::string::npos)
      << w.err;
}

// The shared Kinect grabber frames as PCLZF: read through the depth-image path, with colours.
TEST(CliScripting, SharedPclzfFramesMeshWithColours) {
  const std::string base = "kinect_pcl/grabber_sequences/pclzf";
  if (!test::has_data(base)) GTEST_SKIP() << "shared data not found (MESHFLOW_DATA)";
  const std::string dir = test::temp_dir();
  const nlohmann::json doc =
      parse_json(run_cli("run " + test::data_path(base) + " --voxel 0.01 --json -o " + dir));
  EXPECT_EQ(doc["frames_ok"], 3);
  const TriangleMesh m = io::read_mesh(dir + "/frame_000000.ply");
  EXPECT_GT(m.triangles.size(), 10000u);
  ASSERT_EQ(m.colors.size(), m.vertices.size());
}

}  // namespace
}  // namespace meshflow
