// Reports that scripts read: the same JSON keys with and without --chunk (issue 55, item 6).

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cli_runner.h"

namespace meshflow {
namespace {

nlohmann::json json_of(const test::CliRun& run) {
  EXPECT_EQ(run.exit_code, 0) << run.err;
  try {
    return nlohmann::json::parse(run.out);
  } catch (const nlohmann::json::exception& e) {
    ADD_FAILURE() << e.what() << "\n" << run.out;
    return {};
  }
}

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
}

}  // namespace
}  // namespace meshflow
