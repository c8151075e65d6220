// Reports that scripts read: the same JSON keys with and without --chunk (issue 55, item 6).

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

#include "cli_runner.h"

namespace meshflow {
namespace {

using test::json_of;

TEST(CliReports, ChunkedRunsReportTheKeysOfOneProcess) {
  const std::string dir = test::temp_dir();
  ASSERT_EQ(test::run_cli("sample torus -o " + dir + "/t.ply --points 30000").exit_code, 0);
  const nlohmann::json whole =
      json_of(test::run_cli("reconstruct " + dir + "/t.ply -o " + dir + "/a.ply --json"));
  const nlohmann::json chunked = json_of(test::run_cli(
      "reconstruct " + dir + "/t.ply -o " + dir + "/b.ply --json --chunk 0.3 --voxel " +
      std::to_string(whole["voxel"].get<double>())));
  for (const nlohmann::json* doc : {&whole, &chunked}) {
    ASSERT_TRUE(doc->contains("voxel")) << doc->dump();
    ASSERT_TRUE(doc->contains("mesh")) << doc->dump();
    EXPECT_GT((*doc)["mesh"]["triangles"].get<std::size_t>(), 1000u);
    EXPECT_GT((*doc)["mesh"]["vertices"].get<std::size_t>(), 500u);
  }
  EXPECT_FALSE(chunked.contains("voxel_size"));
  EXPECT_NEAR(chunked["voxel"].get<double>(), whole["voxel"].get<double>(), 1e-6);
  // Every phase of the one process timed, and the serial fraction they imply (issue 61).
  const nlohmann::json& timing = chunked["timing"];
  ASSERT_EQ(timing["ranks"].size(), 1u) << chunked.dump();
  const nlohmann::json& rank = timing["ranks"][0];
  EXPECT_EQ(rank["chunks"], chunked["chunks"]);
  EXPECT_GT(rank["peak_rss_mib"].get<double>(), 1.0);
  std::vector<std::string> names;
  double serial = 0.0, work = 0.0;
  for (const nlohmann::json& p : rank["phases"]) {
    names.push_back(p["phase"].get<std::string>());
    if (p["serial"].get<bool>())
      serial += p["wall_s"].get<double>();
    else
      work += p["work_s"].get<double>();
  }
  // A .ply output is streamed: the weld's plan, the chunks welded and written, then the seams.
  EXPECT_EQ(names, (std::vector<std::string>{"decide", "partition", "chunks", "stitch", "write",
                                             "finish"}));
  EXPECT_NEAR(timing["serial"]["serial_s"].get<double>(), serial, 1e-9);
  EXPECT_NEAR(timing["serial"]["fraction"].get<double>(), serial / (serial + work), 1e-9);
  EXPECT_LE(serial, chunked["wall_s"].get<double>());
}

// run --json names each failed frame with its file, stage and reason (issue 55 item 6).
TEST(CliReports, RunJsonNamesTheFailedFrameAndWhy) {
  const std::string dir = test::temp_dir(), seq = dir + "/seq";
  std::filesystem::create_directories(seq);
  for (const char* name : {"a", "c"})
    ASSERT_EQ(test::run_cli(std::string("sample sphere -o ") + seq + "/" + name +
                            ".ply --points 3000 --seed " + std::to_string(name[0]))
                  .exit_code,
              0);
  test::write_file(seq + "/b.ply",
                   "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\n"
                   "property float y\nproperty float z\nend_header\n0 0 0\n");
  const test::CliRun run = test::run_cli("run " + seq + " -o " + dir + "/out --json");
  const nlohmann::json doc = json_of(run);
  EXPECT_EQ(doc["frames_ok"], 2);
  EXPECT_EQ(doc["frames_failed"], 1);
  ASSERT_EQ(doc["failed_frames"].size(), 1u) << doc.dump();
  const nlohmann::json& failed = doc["failed_frames"][0];
  EXPECT_EQ(failed["index"], 1);
  EXPECT_NE(failed["file"].get<std::string>().find("b.ply"), std::string::npos) << failed;
  EXPECT_EQ(failed["stage"], "read") << failed;
  EXPECT_NE(failed["message"].get<std::string>().find("b.ply"), std::string::npos) << failed;
  EXPECT_FALSE(failed["message"].get<std::string>().empty());
  // A run without failures has the key, empty.
  const nlohmann::json clean =
      json_of(test::run_cli("run " + seq + "/a.ply -o " + dir + "/one --json"));
  EXPECT_TRUE(clean["failed_frames"].is_array());
  EXPECT_TRUE(clean["failed_frames"].empty());
}

}  // namespace
}  // namespace meshflow
