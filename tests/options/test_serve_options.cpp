// The serving options of the option model (options/serve_options.h), shared by the CLI's --serve
// and the Python module's serve(): one parser of the address, one message.

#include "options/serve_options.h"

#include <gtest/gtest.h>

#include <string>

#include "runtime/error.h"

namespace meshflow::options {
namespace {

// The message parse_serve_address() gives for `text`, or "" when it accepts it.
std::string address_problem(const std::string& text) {
  try {
    parse_serve_address(text);
    return "";
  } catch (const Error& e) {
    return e.what();
  }
}

TEST(ServeOptions, ParsesPortHostAndIpv6WithTheLoopbackByDefault) {
  ServeAddress a = parse_serve_address("8080");
  EXPECT_EQ(a.host, "127.0.0.1");  // safe by default
  EXPECT_EQ(a.port, 8080);
  a = parse_serve_address("0.0.0.0:9000");
  EXPECT_EQ(a.host, "0.0.0.0");
  EXPECT_EQ(a.port, 9000);
  a = parse_serve_address("[::1]:0");
  EXPECT_EQ(a.host, "::1");
  EXPECT_EQ(a.port, 0);
  a = parse_serve_address("localhost:65535");
  EXPECT_EQ(a.host, "localhost");
  EXPECT_EQ(a.port, 65535);
}

TEST(ServeOptions, RefusesEveryMalformedAddressNamingServeAndTheText) {
  for (const char* bad : {"",           "x",
                          "abc",        "70000",
                          "65536",      "99999",
                          "123456",     "-1",
                          "+80",        " 80",
                          "80 ",        "8o8o",
                          "host:",      ":8080",
                          ":",          "[::1]",
                          "[::1]80",    "[]:80",
                          "[nope]:80",  "example.org:80",
                          "1.2.3:80",   "256.1.1.1:80",
                          "1.2.3.4:x",  "1.2.3.4:-5",
                          "[::1]:65536"}) {
    const std::string problem = address_problem(bad);
    EXPECT_EQ(problem.rfind("--serve: expected [HOST:]PORT", 0), 0u) << bad << ": " << problem;
    EXPECT_NE(problem.find(std::string("got '") + bad + "'"), std::string::npos) << problem;
  }
  EXPECT_NE(address_problem(":8080").find("empty HOST"), std::string::npos);
}

TEST(ServeOptions, ValidateChecksEachRowAndTheAddressOnlyWhenServing) {
  ServeOptions o;
  EXPECT_NO_THROW(validate(o));  // no server: no address to check
  o.address = "8080";
  EXPECT_NO_THROW(validate(o));
  for (const ServeOptionSpec& spec : serve_option_specs()) {
    EXPECT_EQ(spec.check(o), "") << spec.name;
    EXPECT_NE(std::string(spec.help), "") << spec.name;
  }
  o.address = "abc";
  EXPECT_THROW(validate(o), Error);
  o.address = "0";
  o.rate_mbit = -1.0;
  try {
    validate(o);
    ADD_FAILURE() << "a negative rate passed";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--serve-rate: expected a number in [0, ", 0), 0u)
        << e.what();
  }
  o.rate_mbit = 0.0;
  o.max_viewers = 0;
  EXPECT_THROW(validate(o), Error);
}

}  // namespace
}  // namespace meshflow::options
