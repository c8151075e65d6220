#pragma once
// Runs the meshflow executable built with the tests and captures what it printed.

#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

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

}  // namespace meshflow::test
