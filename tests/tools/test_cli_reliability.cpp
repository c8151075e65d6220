// What a killed process, a full disk and odd paths leave behind: only complete outputs or none,
// and errors that say which file and why.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "cli_runner.h"
#include "test_support.h"

extern char** environ;

namespace meshflow {
namespace {

using test::CliRun;
using test::run_cli;

namespace fs = std::filesystem;

// Starts `meshflow ARGS...` (output to /dev/null), kills it with SIGKILL after `delay`, and
// waits for it. Returns false when it had already finished by then.
bool start_and_kill(const std::vector<std::string>& args, std::chrono::milliseconds delay) {
  std::vector<std::string> argv_strings = {MESHFLOW_CLI};
  argv_strings.insert(argv_strings.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_strings) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) return false;
  std::this_thread::sleep_for(delay);
  const bool killed = kill(pid, SIGKILL) == 0;
  int status = 0;
  waitpid(pid, &status, 0);
  return killed && WIFSIGNALED(status);
}

// Every regular file under `dir` (relative name -> bytes).
std::map<std::string, std::string> files_in(const std::string& dir) {
  std::map<std::string, std::string> files;
  if (!fs::exists(dir)) return files;
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    if (entry.is_regular_file())
      files[fs::relative(entry.path(), dir).string()] = test::read_file(entry.path().string());
  return files;
}

// Runs `args` (with OUT standing for the output directory) once to completion, then `trials`
// times killed at random moments in the last 30 % of its duration (where the outputs are
// written; a little past the end too, as runs vary): after each kill, every output file that
// exists is byte for byte the complete one (temporary "*.tmp" names aside), and a run after the
// kills leaves no temporary name behind.
void expect_only_complete_outputs(const std::vector<std::string>& args, int trials) {
  const auto with_output = [&](const std::string& out) {
    std::vector<std::string> a = args;
    for (std::string& s : a)
      if (s.rfind("OUT", 0) == 0) s = out + s.substr(3);
    return a;
  };
  const std::string reference_dir = test::temp_dir();
  const auto start = std::chrono::steady_clock::now();
  std::string command;
  for (const std::string& a : with_output(reference_dir)) command += " " + a;
  ASSERT_EQ(run_cli(command + " -q").exit_code, 0) << command;
  const auto duration = std::chrono::duration_cast<std::chrono::milliseconds>(
      std::chrono::steady_clock::now() - start);
  const std::map<std::string, std::string> reference = files_in(reference_dir);
  ASSERT_FALSE(reference.empty());

  const std::string dir = test::temp_dir();
  std::mt19937 rng(42);
  std::uniform_int_distribution<long> moment(duration.count() * 7 / 10, duration.count() * 21 / 20);
  for (int t = 0; t < trials; ++t) {
    start_and_kill(with_output(dir), std::chrono::milliseconds(moment(rng)));
    for (const auto& [name, bytes] : files_in(dir)) {
      if (name.size() > 4 && name.compare(name.size() - 4, 4, ".tmp") == 0) continue;
      ASSERT_EQ(reference.count(name), 1u) << name << " is not an output of the run";
      EXPECT_TRUE(bytes == reference.at(name)) << name << " is partial (trial " << t << ")";
    }
  }
  command.clear();
  for (const std::string& a : with_output(dir)) command += " " + a;
  ASSERT_EQ(run_cli(command + " -q").exit_code, 0) << command;
  EXPECT_EQ(files_in(dir), reference) << "a complete run replaces what the killed ones left";
}

TEST(CliReliability, KillNineDuringReconstructLeavesTheMeshCompleteOrAbsent) {
  const std::string dir = test::temp_dir();
  ASSERT_EQ(run_cli("sample torus --points 30000 -o " + dir + "/torus.ply -q").exit_code, 0);
  expect_only_complete_outputs({"reconstruct", dir + "/torus.ply", "-o", "OUT/mesh.ply"}, 12);
}

TEST(CliReliability, KillNineDuringRunLeavesEachFrameCompleteOrAbsent) {
  expect_only_complete_outputs({"run", "--synthetic-depth", "--synthetic-size", "160x120",
                                "--synthetic-frames", "30", "--in-flight", "4", "-o", "OUT"},
                               12);
}

TEST(CliReliability, KillNineDuringFusionLeavesTheMapAndMeshCompleteOrAbsent) {
  expect_only_complete_outputs(
      {"run", "--synthetic-depth", "--synthetic-size", "160x120", "--synthetic-frames", "12",
       "--fuse", "--voxel", "0.03", "-o", "OUT/mesh", "--save-map", "OUT/map.tsdf"},
      6);
}

TEST(CliReliability, OddPathsAreClearErrorsBeforeAnyWork) {
  const std::string dir = test::temp_dir();
  ASSERT_EQ(run_cli("sample sphere --points 2000 -o " + dir + "/s.ply -q").exit_code, 0);
  fs::create_directories(dir + "/taken.ply");
  CliRun r = run_cli("reconstruct " + dir + "/s.ply -o " + dir + "/taken.ply");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("taken.ply: cannot write the output: it is a directory"), std::string::npos)
      << r.err;
  EXPECT_EQ(r.out, "") << "nothing computed";

  ASSERT_EQ(mkfifo((dir + "/pipe.ply").c_str(), 0600), 0);
  r = run_cli("reconstruct " + dir + "/pipe.ply -o " + dir + "/m.ply");  // would block if opened
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("pipe.ply: is a FIFO (named pipe), not a regular file"), std::string::npos)
      << r.err;

  fs::create_directories(dir + "/folder.ply");
  r = run_cli("reconstruct " + dir + "/folder.ply -o " + dir + "/m.ply");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("folder.ply: is a directory, not a file"), std::string::npos) << r.err;

  r = run_cli("reconstruct " + dir + "/s.ply -o " + dir + "/missing/dir/m.ply");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("m.ply: cannot create output file: No such file or directory"),
            std::string::npos)
      << r.err;
}

// A small tmpfs stands for a full disk and a read-only one for a read-only directory (both need
// the right to mount: root with CAP_SYS_ADMIN; skipped otherwise).
class MountedDirectory {
 public:
  explicit MountedDirectory(const std::string& options) : dir_(test::temp_dir() + "/mnt") {
    fs::create_directories(dir_);
    mounted_ =
        std::system(("mount -t tmpfs -o " + options + " tmpfs " + dir_ + " 2>/dev/null").c_str()) ==
        0;
  }
  ~MountedDirectory() {
    if (mounted_) (void)std::system(("umount " + dir_ + " 2>/dev/null").c_str());
  }
  MountedDirectory(const MountedDirectory&) = delete;
  MountedDirectory& operator=(const MountedDirectory&) = delete;
  bool mounted() const { return mounted_; }
  const std::string& path() const { return dir_; }

 private:
  std::string dir_;
  bool mounted_ = false;
};

TEST(CliReliability, AFullDiskStopsTheRunNamingTheFileAndKeepsEarlierOutputs) {
  const MountedDirectory disk("size=1M");
  if (!disk.mounted()) GTEST_SKIP() << "cannot mount a tmpfs here (needs root)";
  const std::string out = disk.path() + "/seq";
  const CliRun r = run_cli(
      "run --synthetic-depth --synthetic-size 160x120 --synthetic-frames 40 "
      "--in-flight 1 -o " +
      out + " -q");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(": write failed: No space left on device"), std::string::npos) << r.err;
  const auto left = files_in(out);
  ASSERT_GT(left.size(), 1u) << "the frames before the disk filled up";
  // The earlier meshes are whole: each reads back as a PLY with its declared triangles.
  const CliRun info = run_cli("eval " + out + "/" + left.begin()->first + " --reference " + out +
                              "/" + left.begin()->first + " -q");
  EXPECT_EQ(info.exit_code, 0) << info.err;
  for (const auto& [name, bytes] : left) EXPECT_EQ(name.find(".tmp"), std::string::npos) << name;
}

TEST(CliReliability, AReadOnlyDirectoryIsAnErrorBeforeAnyWork) {
  const MountedDirectory disk("ro,size=1M");
  if (!disk.mounted()) GTEST_SKIP() << "cannot mount a tmpfs here (needs root)";
  const std::string dir = test::temp_dir();
  ASSERT_EQ(run_cli("sample sphere --points 2000 -o " + dir + "/s.ply -q").exit_code, 0);
  CliRun r = run_cli("reconstruct " + dir + "/s.ply -o " + disk.path() + "/m.ply");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("m.ply: cannot create output file: Read-only file system"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.out, "");
  r = run_cli("run --synthetic-depth --synthetic-size 160x120 -o " + disk.path() + "/seq");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("Read-only file system"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace meshflow
