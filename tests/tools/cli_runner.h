#pragma once
// Runs the meshflow executable built with the tests and captures what it printed.

#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "test_support.h"

namespace meshflow::test {

struct CliRun {
  int exit_code;
  std::string out, err;
};

/// `meshflow ARGS` through the shell (ARGS may hold redirections); stdout and stderr captured.
inline CliRun run_cli(const std::string& args) {
  const std::string dir = temp_dir();
  const std::string cmd =
      std::string(MESHFLOW_CLI) + " " + args + " >" + dir + "/out 2>" + dir + "/err";
  const int status = std::system(cmd.c_str());
  auto slurp = [](const std::string& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  };
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(dir + "/out"), slurp(dir + "/err")};
}

/// The JSON document a successful `run` printed (--json); a test failure, and an empty document,
/// for a non-zero exit or output that is not JSON.
inline nlohmann::json json_of(const CliRun& run) {
  EXPECT_EQ(run.exit_code, 0) << run.err;
  try {
    return nlohmann::json::parse(run.out);
  } catch (const nlohmann::json::exception& e) {
    ADD_FAILURE() << e.what() << "\n" << run.out;
    return {};
  }
}

}  // namespace meshflow::test
