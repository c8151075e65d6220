// --serve's address on every command that takes it (issue 56): a bad address is a usage error
// (exit 2) naming --serve and what it takes, found when the command line is parsed, before any
// input is read; an address in use is a runtime error (exit 1) naming the address.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cli_runner.h"

namespace meshflow {
namespace {

// The commands that take --serve, each with inputs that do not exist (view: an existing file,
// its input is checked by the parser too): a usage error must come before reading them.
std::vector<std::string> serving_commands(const std::string& dir) {
  std::vector<std::string> commands = {
      "run " + dir + "/no_such_sequence -o " + dir + "/out",
      "live " + dir + "/no_such_sequence",
      "reconstruct " + dir + "/no_such_cloud.ply -o " + dir + "/mesh.ply",
  };
#ifdef MESHFLOW_CLI_HAS_VIEW
  test::write_file(dir + "/empty.ply", "");  // never read: the address is refused first
  commands.push_back("view " + dir + "/empty.ply");
#endif
  return commands;
}

TEST(CliServe, BadAddressesAreUsageErrorsOnEveryCommandBeforeAnyInputIsRead) {
  const std::string dir = test::temp_dir();
  const char* bad[] = {"65536",      "70000",           "abc",      "8080x", "-1",
                       ":8080",      "host.invalid:80", "1.2.3:80", "[::1]", "[nope]:80",
                       "127.0.0.1:", "127.0.0.1:99999"};
  for (const std::string& command : serving_commands(dir)) {
    for (const char* address : bad) {
      const test::CliRun r = test::run_cli(command + " '--serve=" + address + "'");
      EXPECT_EQ(r.exit_code, 2) << command << " --serve=" << address << "\n" << r.err;
      EXPECT_NE(r.err.find("--serve"), std::string::npos) << command << ": " << r.err;
      EXPECT_NE(r.err.find("expected [HOST:]PORT"), std::string::npos) << command << ": " << r.err;
      EXPECT_NE(r.err.find(std::string("'") + address + "'"), std::string::npos)
          << command << ": " << r.err;
    }
  }
}

TEST(CliServe, GoodAddressesPassTheParser) {
  // A good address leaves `run` to fail on its missing sequence (exit 1, the path named; it
  // opens the sequence before it starts serving, so nothing is bound here), not on --serve.
  const std::string dir = test::temp_dir();
  for (const char* address :
       {"0", "8080", "65535", "127.0.0.1:0", "0.0.0.0:8080", "localhost:0", "[::1]:0"}) {
    const test::CliRun r = test::run_cli("run " + dir + "/no_such_sequence -o " + dir +
                                         "/out '--serve=" + address + "'");
    EXPECT_EQ(r.exit_code, 1) << address << ": " << r.err;
    EXPECT_NE(r.err.find("no_such_sequence"), std::string::npos) << address << ": " << r.err;
    EXPECT_EQ(r.err.find("--serve"), std::string::npos) << address << ": " << r.err;
  }
}

TEST(CliServe, OtherServingOptionsAreCheckedByTheModel) {
  const std::string dir = test::temp_dir();
  const std::string run = "reconstruct " + dir + "/no_such_cloud.ply -o " + dir + "/m.ply";
  for (const char* bad :
       {" --serve 0 --serve-rate=-1", " --serve 0 --max-viewers 0", " --serve 0 --exit-after x"}) {
    const test::CliRun r = test::run_cli(run + bad);
    EXPECT_EQ(r.exit_code, 2) << bad << ": " << r.err;
    EXPECT_NE(r.err.find("expected"), std::string::npos) << bad << ": " << r.err;
  }
}

#ifdef MESHFLOW_CLI_HAS_VIEW
// A listening socket on 127.0.0.1 holding a port the system chose; closed at the end.
class HeldPort {
 public:
  HeldPort() {
    fd_ = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t size = sizeof a;
    if (fd_ < 0 || bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
        listen(fd_, 1) != 0 || getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &size) != 0)
      port_ = 0;
    else
      port_ = ntohs(a.sin_port);
  }
  ~HeldPort() {
    if (fd_ >= 0) close(fd_);
  }
  HeldPort(const HeldPort&) = delete;
  HeldPort& operator=(const HeldPort&) = delete;
  int port() const { return port_; }

 private:
  int fd_ = -1;
  int port_ = 0;
};

TEST(CliServe, AnAddressInUseIsARuntimeErrorNamingIt) {
  const std::string dir = test::temp_dir();
  ASSERT_EQ(test::run_cli("demo -o " + dir + "/room.ply").exit_code, 0);
  const HeldPort held;
  ASSERT_NE(held.port(), 0) << "could not hold a port on 127.0.0.1";
  const std::string address = "127.0.0.1:" + std::to_string(held.port());
  for (const std::string& command :
       {"view " + dir + "/room.ply --exit-after 0.01 --serve " + address,
        "run --synthetic-depth --synthetic-frames 1 --synthetic-size 64x48 -o " + dir +
            "/run --exit-after 0.01 --serve " + std::to_string(held.port())}) {
    const test::CliRun r = test::run_cli(command);
    EXPECT_EQ(r.exit_code, 1) << command << "\n" << r.err;
    EXPECT_NE(r.err.find(address), std::string::npos) << command << ": " << r.err;
  }
}
#endif

}  // namespace
}  // namespace meshflow
