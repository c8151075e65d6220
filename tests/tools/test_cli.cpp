// Runs the meshflow executable: exit codes, error messages and no partial output.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "nodes/io/mesh_readers.h"
#include "nodes/io/read_point_cloud.h"
#include "test_support.h"
#include "tools/cli_runner.h"

namespace meshflow {
namespace {

using test::CliRun;
using test::run_cli;

TEST(Cli, BrokenInputsFailWithOneLineNamingTheFileAndNoOutput) {
  const std::string out_dir = test::temp_dir();
  for (const char* name :
       {"truncated_binary.ply", "count_too_large.ply", "count_too_small.ply", "non_numeric.ply",
        "empty.ply", "unknown_type.ply", "huge_coordinates.ply", "nan_rows.xyz", "overflow.xyz",
        "bad_columns.xyz", "empty.pcd", "truncated.pcd", "inconsistent_header.pcd", "truncated.3d",
        "not_a_ply.ply", "partial_normals.ply", "partial_normals.pcd"}) {
    const std::string input = test::fixture(std::string("bad/") + name);
    const std::string output = out_dir + "/" + name + ".ply";
    const CliRun r = run_cli("reconstruct " + input + " -o " + output);
    EXPECT_EQ(r.exit_code, 1) << name << ": " << r.err;
    EXPECT_NE(r.err.find(input), std::string::npos) << name << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(std::filesystem::exists(output)) << name;
    EXPECT_FALSE(std::filesystem::exists(output + ".tmp")) << name;
  }
}

TEST(Cli, UsageErrorsExitWithTwo) {
  EXPECT_EQ(run_cli("").exit_code, 2);
  EXPECT_EQ(run_cli("reconstruct").exit_code, 2);
  EXPECT_EQ(run_cli("reconstruct a.ply -o b.ply --kn 1").exit_code, 2);
  EXPECT_EQ(run_cli("frobnicate").exit_code, 2);
  EXPECT_EQ(run_cli("--help").exit_code, 0);
}

// CLI11's own checks let NaN through and wrap "-1" for unsigned options; every number is
// checked by tools/cli_checks.h instead, and the message names the option and the value.
TEST(Cli, NonFiniteNegativeAndOutOfRangeNumbersAreUsageErrors) {
  for (const char* option :
       {"--voxel nan", "--voxel -1", "--voxel inf", "--voxel 1e39", "--max-distance nan",
        "--min-component -1", "--max-hole -1", "--filter-voxel nan", "--min-range nan",
        "--decimate-to nan", "--outlier-k 100000", "--max-frames -1", "--threads -2"}) {
    const std::string command = std::string("run --synthetic -o out ") + option;
    const CliRun r = run_cli(command);
    EXPECT_EQ(r.exit_code, 2) << command << ": " << r.err;
    const std::string name = std::string(option).substr(0, std::string(option).find(' '));
    EXPECT_NE(r.err.find(name + ":"), std::string::npos) << command << ": " << r.err;
  }
  for (const char* option : {"--rate nan", "--decimate nan", "--rqt-error -1"}) {
    const CliRun r = run_cli(std::string("live --synthetic-depth ") + option);
    EXPECT_EQ(r.exit_code, 2) << option << ": " << r.err;
  }
  EXPECT_EQ(run_cli("demo --noise nan").exit_code, 2);
  EXPECT_EQ(run_cli("run --synthetic -o out --fuse --truncation nan").exit_code, 2);
}

TEST(Cli, MissingFileAndUnknownFormat) {
  const std::string out = test::temp_dir() + "/m.ply";
  CliRun r = run_cli("reconstruct /nonexistent/cloud.ply -o " + out);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("cannot open"), std::string::npos) << r.err;
  r = run_cli("reconstruct cloud.e57 -o " + out);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("unknown point cloud format"), std::string::npos) << r.err;
}

TEST(Cli, ReconstructsAndReportsDroppedNaNRows) {
  const std::string out = test::temp_dir() + "/plane.obj";
  const CliRun r = run_cli("reconstruct " + test::fixture("good/plane_with_nan_rows.xyz") + " -o " +
                           out + " --voxel 0.05 --threads 2");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("dropped 2 non-finite"), std::string::npos) << r.err;
  EXPECT_TRUE(std::filesystem::exists(out));
  EXPECT_NE(r.out.find("normals"), std::string::npos) << "prints the per-stage table";
}

TEST(Cli, InfoAndDemo) {
  CliRun r = run_cli("info " + test::fixture("good/plane_with_nan_rows.xyz"));
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("1600 (1598 finite, 2 NaN/Inf)"), std::string::npos) << r.out;
  // An organized 5 x 4 cloud of a pinhole camera (fx 100, fy 80, cx 2, cy 1.5) looking at a
  // slanted plane: info recognises the camera.
  std::string pcd =
      "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 5\nHEIGHT 4\n"
      "POINTS 20\nDATA ascii\n";
  for (int v = 0; v < 4; ++v)
    for (int u = 0; u < 5; ++u) {
      const double z = 1.0 + 0.1 * u + 0.05 * v;
      pcd += std::to_string((u - 2.0) * z / 100.0) + " " + std::to_string((v - 1.5) * z / 80.0) +
             " " + std::to_string(z) + "\n";
    }
  const std::string pcd_path = test::temp_dir() + "/pinhole.pcd";
  test::write_file(pcd_path, pcd);
  r = run_cli("info " + pcd_path);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("organized   5 x 4, a pinhole view: fx 100.0"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("cy 1.50"), std::string::npos) << r.out;
  const std::string out = test::temp_dir() + "/demo.ply";
  r = run_cli("demo --voxel 0.1 -o " + out);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("accuracy"), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(out));
}

TEST(Cli, AnObjectWithoutASensorIsMeshedWatertightAndMeasuredAgainstItsTruth) {
  const std::string dir = test::temp_dir();
  CliRun r = run_cli("sample torus --points 30000 -o " + dir + "/torus.ply");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_cli("info " + dir + "/torus.ply");
  EXPECT_NE(r.out.find("--orient auto = propagate"), std::string::npos) << r.out;
  r = run_cli("reconstruct " + dir + "/torus.ply -o " + dir + "/mesh.ply --voxel 0.02");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("oriented by propagation (1 component"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("(extended marching cubes, sharp-feature normals)"), std::string::npos)
      << "clean samples without a sensor: extended marching cubes by default\n"
      << r.out;
  r = run_cli("eval " + dir + "/mesh.ply --object torus");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("(watertight)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("surface -> truth"), std::string::npos) << r.out;

  // With exact normals in the file they are used as they are; --normals estimate re-estimates.
  r = run_cli("sample chamfered-cube --points 30000 --normals -o " + dir + "/cube.ply");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_cli("reconstruct " + dir + "/cube.ply -o " + dir + "/cube_mesh.ply --voxel 0.02");
  EXPECT_NE(r.out.find("normals    from the input"), std::string::npos) << r.out;
  r = run_cli("reconstruct " + dir + "/cube.ply -o " + dir +
              "/cube_mesh.ply --voxel 0.02 --normals estimate --orient input");
  EXPECT_NE(r.out.find("), oriented as the input normals"), std::string::npos) << r.out;
  r = run_cli("reconstruct " + dir + "/cube.ply -o " + dir +
              "/cube_mesh.ply --voxel 0.02 --normals estimate --orient away=0,0,0");
  EXPECT_NE(r.out.find("), oriented away from the viewpoint"), std::string::npos) << r.out;
}

TEST(Cli, OrientationAndObjectUsageErrors) {
  EXPECT_EQ(run_cli("reconstruct a.ply -o b.ply --orient sideways").exit_code, 2);
  EXPECT_EQ(run_cli("reconstruct a.ply -o b.ply --orient viewpoint=1,2").exit_code, 2);
  EXPECT_EQ(run_cli("reconstruct a.ply -o b.ply --orient viewpoint=1,2,nan").exit_code, 2);
  EXPECT_EQ(run_cli("reconstruct a.ply -o b.ply --normals guess").exit_code, 2);
  EXPECT_EQ(run_cli("sample teapot -o x.ply").exit_code, 2);
  EXPECT_EQ(run_cli("eval m.ply --object teapot").exit_code, 2);
  EXPECT_EQ(run_cli("eval m.ply --object torus --reference r.ply").exit_code, 2);
  // A file without normals cannot be meshed with --normals input: one line naming why.
  const std::string dir = test::temp_dir();
  ASSERT_EQ(run_cli("sample sphere --points 2000 -o " + dir + "/s.ply").exit_code, 0);
  const CliRun r = run_cli("reconstruct " + dir + "/s.ply -o " + dir + "/m.ply --normals input");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("carries no normals"), std::string::npos) << r.err;
}

// A 3DTK scan whose second line ends after two numbers.
constexpr const char* kTruncatedScan = "100 0 50\n120 10\n";

// Writes dir/name.3d with `points` and an identity pose beside it.
void write_scan(const std::string& dir, const std::string& name, const std::string& points) {
  test::write_file(dir + "/" + name + ".3d", points);
  test::write_file(dir + "/" + name + ".pose", "0 0 0\n0 0 0\n");
}

// A 3DTK directory with a good scan, a truncated one and another good one.
std::string scan_directory_with_a_bad_frame() {
  const std::string dir = test::temp_dir();
  std::string scan;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j)
      scan += std::to_string(2 * i - 40) + " " + std::to_string(2 * j - 40) + " 300\n";
  for (const char* name : {"scan000", "scan001", "scan002"})
    write_scan(dir, name, std::string(name) == "scan001" ? kTruncatedScan : scan);
  return dir;
}

// A LAS 1.2 file (point format 0, 0.1 mm resolution) of `cloud`'s points moved by `offset`.
std::string las_of(const PointCloud& cloud, const Eigen::Vector3d& offset) {
  std::string h(227, '\0');
  const auto put = [&h](std::size_t at, const auto& v) { std::memcpy(&h[at], &v, sizeof v); };
  std::memcpy(&h[0], "LASF", 4);
  h[24] = 1;
  h[25] = 2;
  put(94, std::uint16_t{227});
  put(96, std::uint32_t{227});
  put(105, std::uint16_t{20});
  put(107, static_cast<std::uint32_t>(cloud.size()));
  for (int k = 0; k < 3; ++k) {
    put(131 + 8 * k, 1e-4);
    put(155 + 8 * k, offset[k]);
  }
  for (const Eigen::Vector3f& p : cloud.positions) {
    std::string r(20, '\0');
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<std::int32_t>(std::lround(p[k] / 1e-4));
      std::memcpy(&r[4 * static_cast<std::size_t>(k)], &v, 4);
    }
    h += r;
  }
  return h;
}

// A georeferenced LAS (UTM-like, 4 800 km) is meshed in a local frame: the same triangles as
// the same points near the world origin, the PLY's vertices in world coordinates (doubles), the
// origin in the report.
TEST(Cli, GeoreferencedLasIsMeshedInALocalFrameAndWrittenInTheWorld) {
  const std::string dir = test::temp_dir();
  ASSERT_EQ(run_cli("sample sphere --points 20000 -o " + dir + "/s.ply -q").exit_code, 0);
  const PointCloud sphere = io::read_point_cloud(dir + "/s.ply");
  const Eigen::Vector3d utm(512000.0, 4812000.0, 0.0);  // the origin the reader picks
  test::write_file(dir + "/utm.las", las_of(sphere, utm));
  test::write_file(dir + "/local.las", las_of(sphere, Eigen::Vector3d::Zero()));
  CliRun r = run_cli("reconstruct " + dir + "/utm.las -o " + dir + "/utm.ply --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto world = nlohmann::json::parse(r.out);
  EXPECT_EQ(world["origin"], (nlohmann::json{512000.0, 4812000.0, 0.0}));
  r = run_cli("reconstruct " + dir + "/local.las -o " + dir + "/local.ply --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto local = nlohmann::json::parse(r.out);
  EXPECT_EQ(world["mesh"]["triangles"], local["mesh"]["triangles"]);
  EXPECT_EQ(world["mesh"]["vertices"], local["mesh"]["vertices"]);
  // The first vertex: the local run's plus the UTM offset, in doubles, to a millimetre.
  const TriangleMesh local_mesh = io::read_mesh(dir + "/local.ply");
  const std::string ply = test::read_file(dir + "/utm.ply");
  EXPECT_NE(ply.find("property double x"), std::string::npos);
  double first[3];
  std::memcpy(first, ply.data() + ply.find("end_header\n") + 11, sizeof first);
  const Eigen::Vector3d expected = local_mesh.vertices[0].cast<double>() + utm;
  EXPECT_LT((Eigen::Vector3d(first[0], first[1], first[2]) - expected).norm(), 1e-3);
  r = run_cli("reconstruct " + dir + "/utm.las -o " + dir + "/utm2.ply");
  EXPECT_NE(r.out.find("origin     512000.000 4812000.000 0.000"), std::string::npos) << r.out;
}

// --max-memory: a voxel far too small for the input is an error naming the input and the
// limit, not an out-of-memory kill; sizes take K/M/G suffixes; malformed sizes are usage errors.
TEST(Cli, MaxMemoryRefusesAGridThatWouldNotFit) {
  const std::string dir = test::temp_dir();
  CliRun r = run_cli("sample torus -o " + dir + "/torus.ply -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_cli("reconstruct " + dir + "/torus.ply -o " + dir + "/mesh.ply --voxel 0.002 " +
              "--max-memory 4M");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(dir + "/torus.ply: memory:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("past the limit of 4 MiB (--max-memory)"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/mesh.ply"));
  r = run_cli("reconstruct " + dir + "/torus.ply -o " + dir + "/mesh.ply --max-memory 1G -q");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  for (const char* bad : {"4X", "-1M", "nan", "G"}) {
    r = run_cli("reconstruct " + dir + "/torus.ply -o " + dir + "/x.ply --max-memory " + bad);
    EXPECT_EQ(r.exit_code, 2) << bad;
    EXPECT_NE(r.err.find("expected a size such as 512M"), std::string::npos) << r.err;
  }
}

TEST(Cli, RunReportsABadFrameAndContinuesStrictStops) {
  const std::string seq = scan_directory_with_a_bad_frame();
  const std::string out = test::temp_dir();
  CliRun r = run_cli("run " + seq + " -o " + out + " --voxel 0.05 --in-flight 2");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("frame 1 ("), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("scan001.3d: line 2"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("2 ok, 1 failed"), std::string::npos) << r.out;
  EXPECT_TRUE(std::filesystem::exists(out + "/frame_000000.ply"));
  EXPECT_FALSE(std::filesystem::exists(out + "/frame_000001.ply"));
  EXPECT_TRUE(std::filesystem::exists(out + "/frame_000002.ply"));

  const std::string strict_out = test::temp_dir();
  r = run_cli("run " + seq + " -o " + strict_out + " --voxel 0.05 --in-flight 1 --strict");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("--strict"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(strict_out + "/frame_000002.ply"));
}

// Issue 55: three points gave reconstruct exit 1 but run "1 ok" and a 0-triangle mesh. Now the
// frame fails in a stage on every path: reconstruct exits 1, run counts a failed frame with the
// reason (and fails, as no frame was meshed) and leaves no output directory behind.
TEST(Cli, ADegenerateCloudIsAnErrorForReconstructAndAFailedFrameForRun) {
  const std::string dir = test::temp_dir();
  test::write_file(dir + "/three.xyz", "0 0 0\n1 0 0\n0 1 0\n");
  CliRun r = run_cli("reconstruct " + dir + "/three.xyz -o " + dir + "/m.ply");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("three.xyz"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/m.ply"));

  r = run_cli("run " + dir + "/three.xyz -o " + dir + "/out/frames");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.out.find("0 ok, 1 failed"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("frame 0 ("), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("triangle"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/out")) << "the empty directories it made are gone";

  // With a good frame beside it: one ok, one failed, exit 0; the directory stays with its mesh.
  const std::string seq = dir + "/seq";
  std::filesystem::create_directories(seq);
  ASSERT_EQ(run_cli("sample sphere --points 4000 -q -o " + seq + "/a.ply").exit_code, 0);
  test::write_file(seq + "/b.ply",
                   "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float "
                   "y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n");
  r = run_cli("run " + seq + " -o " + dir + "/both --voxel 0.05");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("1 ok, 1 failed"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("frame 1 ("), std::string::npos) << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir + "/both/frame_000000.ply"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/both/frame_000001.ply"));
}

// -o of run is a directory: a mesh file's name is a usage error, and nothing is created.
TEST(Cli, RunOutputIsADirectoryNotAMeshFile) {
  const std::string dir = test::temp_dir();
  for (const char* name : {"out.ply", "out.OBJ", "out.mfc", "out.glb"}) {
    const CliRun r = run_cli("run --synthetic --max-frames 1 -o " + dir + "/" + name);
    EXPECT_EQ(r.exit_code, 2) << name << ": " << r.err;
    EXPECT_NE(r.err.find("give a directory"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("mesh file"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir + "/" + name)) << name;
  }
}

// An empty directory (or one of unrelated files) is no sequence: the message says what was
// looked for, not just "no scanNNN.3d files".
TEST(Cli, ADirectoryWithoutASequenceSaysWhatWasLookedFor) {
  const std::string dir = test::temp_dir() + "/empty";
  std::filesystem::create_directories(dir);
  CliRun r = run_cli("run " + dir + " -o " + dir + "/../out");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("holds no recognisable sequence (the directory is empty)"),
            std::string::npos)
      << r.err;
  for (const char* kind : {"scanNNN.3d", "*.pcd", "*.ply", "depth", "Redwood", "TUM"})
    EXPECT_NE(r.err.find(kind), std::string::npos) << kind << ": " << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/../out"));
  test::write_file(dir + "/notes.txt", "hello\n");
  r = run_cli("run " + dir + " -o " + dir + "/../out");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("1 entry, not a frame"), std::string::npos) << r.err;
}

TEST(Cli, LiveSkipsAnUnreadableFrameAndReplaysTheOthers) {
  const std::string seq = scan_directory_with_a_bad_frame();
  CliRun r = run_cli("live " + seq + " --voxel 0.05 --rate 1000 --policy queue --waiting 8");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("frame 1 ("), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("scan001.3d: line 2"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("2 frames (1 unreadable, skipped)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("2 pushed, 2 delivered (0 failed)"), std::string::npos) << r.out;
  // A sequence of nothing but the bad frame: nothing to replay, and the message says why.
  const std::string bad_only = test::temp_dir();
  write_scan(bad_only, "scan000", kTruncatedScan);
  r = run_cli("live " + bad_only + " --voxel 0.05");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("none readable (1 skipped)"), std::string::npos) << r.err;
}

// Frames pushed faster than the volumetric path meshes them are dropped (realtime policy), and
// the report names the per-frame path that keeps up with a depth camera; --triangulate has no
// faster path to name.
TEST(Cli, LiveNamesTheFastPathWhenFramesAreDropped) {
  const std::string replay =
      "live --synthetic-depth --synthetic-size 160x120 --max-frames 8 --rate 10000 --waiting 1 "
      "--no-warm-up";
  const CliRun volumetric = run_cli(replay);
  ASSERT_EQ(volumetric.exit_code, 0) << volumetric.err;
  EXPECT_EQ(volumetric.out.find(" 0 dropped"), std::string::npos) << volumetric.out;
  EXPECT_NE(volumetric.out.find("--triangulate rqt meshes each depth image directly"),
            std::string::npos)
      << volumetric.out;
  const CliRun triangulated = run_cli(replay + " --triangulate rqt");
  ASSERT_EQ(triangulated.exit_code, 0) << triangulated.err;
  EXPECT_EQ(triangulated.out.find("--triangulate rqt meshes"), std::string::npos)
      << triangulated.out;
}

// The warm-up (--warm-up, the default) meshes a short sequence's frames over again (the allocator's
// pools are still growing after a few frames), up to 32 frames or a second, before the timed
// replay, which is unchanged.
TEST(Cli, LiveWarmUpCyclesAShortSequence) {
  const CliRun r = run_cli(
      "live --synthetic-depth --max-frames 3 --triangulate rqt --rate 1000 --warm-up "
      "--policy queue --waiting 8");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const std::string label = "warm-up    ";  // then the number of frames meshed
  const std::size_t at = r.out.find(label);
  ASSERT_NE(at, std::string::npos) << r.out;
  const int warmed = std::stoi(r.out.substr(at + label.size()));
  EXPECT_GT(warmed, 3) << r.out;  // more than one round (a round takes well under the second)
  EXPECT_LE(warmed, 32) << r.out;
  EXPECT_NE(r.out.find("3 pushed, 3 delivered (0 failed)"), std::string::npos) << r.out;
  // The warm-up is on without the flag (issue 55 item 8: first frames were dropped for start-up
  // costs); --no-warm-up times a cold start.
  const std::string replay = "live --synthetic-depth --max-frames 3 --triangulate rqt --rate 1000";
  CliRun d = run_cli(replay);
  EXPECT_EQ(d.exit_code, 0) << d.err;
  EXPECT_NE(d.out.find(label), std::string::npos) << d.out;
  d = run_cli(replay + " --no-warm-up");
  EXPECT_EQ(d.exit_code, 0) << d.err;
  EXPECT_EQ(d.out.find(label), std::string::npos) << d.out;
}

TEST(Cli, RunMergedAndUsageErrors) {
  const std::string out = test::temp_dir();
  CliRun r = run_cli("run --synthetic --max-frames 2 --merged -o " + out + " --voxel 0.1");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(out + "/merged.ply"));
  EXPECT_NE(r.out.find("merged     "), std::string::npos) << r.out;
  r = run_cli("run --synthetic --max-frames 2 --concatenate -o " + out + " --voxel 0.1");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(out + "/concatenated.ply"));
  EXPECT_EQ(run_cli("run -o " + out).exit_code, 2) << "neither SEQUENCE nor --synthetic";
  EXPECT_EQ(run_cli("run --synthetic -o " + out + " --merged --per-frame").exit_code, 2);
  EXPECT_EQ(run_cli("run --synthetic -o " + out + " --merged --concatenate").exit_code, 2);
  EXPECT_EQ(run_cli("run --synthetic-depth -o " + out + " --merged --triangulate rqt").exit_code,
            2);
}

// --close where there is no distance field of the whole object to fill is a usage error, not
// a flag silently ignored (triangulated depth images) or a failure after the input
// was partitioned (--chunk); a whole number out of any integer's range is refused before it is
// converted.
TEST(Cli, CloseWhereItCannotWorkAndOutOfRangeNumbersAreUsageErrors) {
  const std::string out = test::temp_dir();
  EXPECT_EQ(run_cli("run --synthetic-depth -o " + out + " --triangulate rqt --close").exit_code, 2);
  EXPECT_EQ(run_cli("live --synthetic-depth --triangulate rqt --close").exit_code, 2);
  EXPECT_EQ(run_cli("reconstruct a.ply -o b.ply --chunk 2 --close").exit_code, 2);
  const CliRun huge = run_cli("reconstruct a.ply -o b.ply --outlier-cluster 1e20");
  EXPECT_EQ(huge.exit_code, 2);
  EXPECT_NE(huge.err.find("in range"), std::string::npos) << huge.err;
  EXPECT_EQ(run_cli("reconstruct a.ply -o b.ply --outlier-cluster -1e30").exit_code, 2);
}

TEST(Cli, RunTriangulatesDepthFramesPerFrame) {
  const std::string out = test::temp_dir();
  CliRun r =
      run_cli("run --synthetic-depth --max-frames 2 --triangulate rqt --decimate 0.25 -o " + out);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("2 ok, 0 failed"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("triangulate"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("voxelize"), std::string::npos) << r.out;
  EXPECT_TRUE(std::filesystem::exists(out + "/frame_000000.ply"));
  EXPECT_TRUE(std::filesystem::exists(out + "/frame_000001.ply"));
  // Laser scans are not organized: every frame fails, saying why, and the run fails.
  r = run_cli("run --synthetic --max-frames 1 --triangulate naive -o " + test::temp_dir());
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("organized point cloud"), std::string::npos) << r.err;
  EXPECT_EQ(run_cli("run --synthetic-depth --fuse --triangulate rqt -o " + out).exit_code, 2);
  EXPECT_EQ(run_cli("run --synthetic-depth --triangulate quads -o " + out).exit_code, 2);
}

// An organized PCD (ASCII, 40 x 32, fx = fy = 100 from the origin): a coloured wall of 30 x 30
// points at 2 m, and in the NaN margin around it two specks of 2 x 2 and 3 x 2 points.
std::string organized_coloured_pcd(const std::string& dir) {
  std::ostringstream pcd;
  pcd << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\n"
         "COUNT 1 1 1 1\nWIDTH 40\nHEIGHT 32\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1280\n"
         "DATA ascii\n";
  for (int v = 0; v < 32; ++v)
    for (int u = 0; u < 40; ++u) {
      const bool wall = u < 30 && v < 30;
      const bool speck =
          (u >= 33 && u < 35 && v >= 5 && v < 7) || (u >= 33 && u < 36 && v >= 15 && v < 17);
      const std::uint32_t rgb = (4u * u) << 16 | (5u * v) << 8 | 200u;
      if (wall || speck)
        pcd << (u - 20) * 0.02 << ' ' << (v - 16) * 0.02 << " 2 " << rgb << '\n';
      else
        pcd << "nan nan nan " << rgb << '\n';
    }
  const std::string path = dir + "/wall.pcd";
  test::write_file(path, pcd.str());
  return path;
}

// `run --triangulate` on an organized PCD: the mesh keeps the points' colours and gets vertex
// normals (as the same frame read as depth and colour images does), and specks below
// --min-component triangles are removed and counted, by default (the clean step's rule).
TEST(Cli, RunTriangulateOnAnOrganizedPcdKeepsColoursAndRemovesSpecks) {
  const std::string pcd = organized_coloured_pcd(test::temp_dir());
  for (const char* method : {"naive", "rqt"}) {
    const std::string out = test::temp_dir();
    CliRun r = run_cli("run " + pcd + " --triangulate " + std::string(method) + " -o " + out);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("components 2 of 3 removed for having fewer than 20 triangles (6 "
                         "triangles)"),
              std::string::npos)
        << r.out;
    const TriangleMesh mesh = io::read_mesh(out + "/frame_000000.ply");
    ASSERT_GT(mesh.triangles.size(), 0u) << method;
    ASSERT_EQ(mesh.colors.size(), mesh.vertices.size()) << method;
    ASSERT_EQ(mesh.normals.size(), mesh.vertices.size()) << method;
    for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {  // the point's own colour
      const int u = static_cast<int>(std::lround(mesh.vertices[v].x() / 0.02f)) + 20;
      const int row = static_cast<int>(std::lround(mesh.vertices[v].y() / 0.02f)) + 16;
      EXPECT_EQ(mesh.colors[v],
                (Rgb8{static_cast<std::uint8_t>(4 * u), static_cast<std::uint8_t>(5 * row), 200}))
          << method << " vertex " << v;
      EXPECT_LT(mesh.normals[v].z(), -0.99f) << "towards the camera";
    }
    float right = -1.0f;
    for (const Eigen::Vector3f& p : mesh.vertices) right = std::max(right, p.x());
    EXPECT_LT(right, 0.2f) << "no speck (they lie at x >= 0.26)";
    // --min-component 0 keeps them; --json names the counts.
    const std::string all = test::temp_dir();
    r = run_cli("run " + pcd + " --triangulate " + std::string(method) +
                " --min-component 0 --json -o " + all);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json doc = nlohmann::json::parse(r.out);
    EXPECT_EQ(doc["components"]["components"], 3) << r.out;
    EXPECT_EQ(doc["components"]["removed_components"], 0) << r.out;
    EXPECT_EQ(io::read_mesh(all + "/frame_000000.ply").triangles.size(), mesh.triangles.size() + 6);
  }
}

// The Kinect frames as PCD keep their colours on the per-frame path, like the TIFF copies of
// the same frames; office1's specks (217 of its 241 components) are removed.
TEST(Cli, RunTriangulateKeepsKinectPcdColoursLikeTheImageCopies) {
  MESHFLOW_REQUIRE_DATA("kinect_pcl/grabber_sequences/pcd");
  for (const char* input : {"kinect_pcl/grabber_sequences/pcd", "kinect_pcl/grabber_sequences/tiff",
                            "kinect_pcl/office1.pcd"}) {
    const std::string out = test::temp_dir();
    const CliRun r =
        run_cli("run " + test::data_path(input) + " --triangulate naive --max-frames 1 -o " + out);
    ASSERT_EQ(r.exit_code, 0) << input << ": " << r.err;
    const TriangleMesh mesh = io::read_mesh(out + "/frame_000000.ply");
    EXPECT_GT(mesh.triangles.size(), 100000u) << input;
    EXPECT_EQ(mesh.colors.size(), mesh.vertices.size()) << input;
    EXPECT_EQ(mesh.normals.size(), mesh.vertices.size()) << input;
    std::printf("[ cli ] %s: %s", input, r.out.substr(r.out.find("components ")).c_str());
  }
}

// The cloud path's clean step on a Kinect frame: splitting its non-manifold vertices left 68
// coincident vertex pairs, which a reader that welds on load (Open3D's OBJ / glTF readers,
// trimesh) joined into 68 non-manifold vertices again (80 non-manifold edges once the holes
// step had filled loops through the copies). Removing the smaller fans leaves none.
TEST(Cli, KinectFrameMeshHasNoCoincidentVerticesToWeld) {
  MESHFLOW_REQUIRE_DATA("kinect_pcl/grabber_sequences/pcd/frame_20121214T142255.814212.pcd");
  const std::string out = test::temp_dir() + "/frame.ply";
  const CliRun r =
      run_cli("reconstruct " +
              test::data_path("kinect_pcl/grabber_sequences/pcd/frame_20121214T142255.814212.pcd") +
              " -o " + out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const TriangleMesh mesh = io::read_mesh(out);
  const test::WeldedTopology welded = test::welded_topology(mesh);
  std::printf(
      "[ cli ] grabber frame 0: %zu triangles, %zu coincident vertex pairs, welded: %zu "
      "non-manifold vertices, %zu non-manifold edges\n",
      mesh.triangles.size(), welded.coincident_pairs, welded.non_manifold_vertices,
      welded.non_manifold_edges);
  EXPECT_GT(mesh.triangles.size(), 150000u);
  EXPECT_EQ(welded.coincident_pairs, 0u);
  EXPECT_EQ(welded.non_manifold_vertices, 0u);
  EXPECT_EQ(welded.non_manifold_edges, 0u);
}

TEST(Cli, ProfileWritesTraceAndCsv) {
  const std::string dir = test::temp_dir();
  const CliRun r = run_cli("profile --synthetic --max-frames 3 --in-flight 2 --voxel 0.1 --trace " +
                           dir + "/trace.json --csv " + dir + "/stages.csv");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  for (const char* stage : {"read", "normals", "distance", "extract"}) {
    EXPECT_NE(r.out.find(stage), std::string::npos) << r.out;
  }
  EXPECT_NE(r.out.find("p50 ms"), std::string::npos);
  std::ifstream trace(dir + "/trace.json");
  const nlohmann::json json = nlohmann::json::parse(trace);
  ASSERT_TRUE(json.contains("traceEvents"));
  EXPECT_EQ(json["traceEvents"].size(), 3u * 8u);
  std::set<std::uint64_t> frames;
  for (const auto& e : json["traceEvents"]) {
    EXPECT_EQ(e["ph"], "X");
    EXPECT_GE(e["dur"].get<double>(), 0.0);
    frames.insert(e["args"]["frame"].get<std::uint64_t>());
  }
  EXPECT_EQ(frames.size(), 3u);
  std::ifstream csv(dir + "/stages.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header.rfind("stage,calls,total_ms", 0), 0u);
}

}  // namespace
}  // namespace meshflow
