// --crop minx,miny,minz,maxx,maxy,maxz on reconstruct and run (issue 55 item 9): the points
// outside the box are dropped right after reading; a bad box is a usage error naming --crop.

#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "cli_runner.h"
#include "nodes/eval/mesh_statistics.h"
#include "nodes/io/mesh_readers.h"

namespace meshflow {
namespace {

TEST(CliCrop, ReconstructAndRunKeepTheBoxOnly) {
  const std::string dir = test::temp_dir();
  ASSERT_EQ(test::run_cli("sample sphere -o " + dir + "/s.ply --points 40000").exit_code, 0);
  // The upper half of the 0.5 m sphere about the origin: an open cap with one border.
  const std::string crop = " --crop=-1,-1,0.1,1,1,1";
  const test::CliRun rec =
      test::run_cli("reconstruct " + dir + "/s.ply -o " + dir + "/cap.ply --json" + crop);
  ASSERT_EQ(rec.exit_code, 0) << rec.err;
  const nlohmann::json doc = nlohmann::json::parse(rec.out);
  EXPECT_GT(doc["filter"]["cropped"].get<std::size_t>(), 20000u) << doc["filter"].dump();
  const MeshStatistics cap = mesh_statistics(io::read_mesh(dir + "/cap.ply"));
  EXPECT_FALSE(cap.closed);
  EXPECT_EQ(cap.topology.boundary_loops, 1u);
  EXPECT_GT(cap.bounds.min().z(), 0.1f - 0.03f);
  EXPECT_NEAR(cap.bounds.max().z(), 0.5f, 0.02f);
  // A spherical cap of height h = 0.4 m on a 0.5 m sphere: area 2 pi r h.
  EXPECT_NEAR(cap.area, 2 * 3.14159265 * 0.5 * 0.4, 0.05 * 2 * 3.14159265 * 0.5 * 0.4);

  const test::CliRun run = test::run_cli("run " + dir + "/s.ply -o " + dir + "/run --json" + crop);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(nlohmann::json::parse(run.out)["frames_ok"], 1);
  for (const auto& entry : std::filesystem::directory_iterator(dir + "/run")) {
    const MeshStatistics s = mesh_statistics(io::read_mesh(entry.path().string()));
    EXPECT_GT(s.bounds.min().z(), 0.1f - 0.03f) << entry.path();
  }
}

TEST(CliCrop, BadBoxesAreUsageErrorsAndAnEmptyBoxFailsTheFrame) {
  const std::string dir = test::temp_dir();
  ASSERT_EQ(test::run_cli("sample sphere -o " + dir + "/s.ply --points 2000").exit_code, 0);
  test::CliRun r = test::run_cli("reconstruct " + dir + "/s.ply -o " + dir + "/m.ply --crop 1,2,3");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--crop: expected six numbers"), std::string::npos) << r.err;
  r = test::run_cli("run " + dir + "/s.ply -o " + dir + "/r --crop 0,0,1,1,1,0.5");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("minz must be below maxz"), std::string::npos) << r.err;
  r = test::run_cli("reconstruct " + dir + "/s.ply -o " + dir + "/m.ply --crop 5,5,5,6,6,6");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("outside the crop box"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/m.ply"));
}

}  // namespace
}  // namespace meshflow
