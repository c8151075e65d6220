#include "options/serve_options.h"

#include <arpa/inet.h>

#include <algorithm>

#include "options/pipeline_options.h"
#include "runtime/error.h"

namespace meshflow::options {
namespace {

using S = ServeOptions;

// What --serve takes, for every message about it.
constexpr const char* kServeExpected =
    "expected [HOST:]PORT: PORT a whole number in [0, 65535] (0: any free port), HOST an IPv4 "
    "address, localhost or [IPv6] (127.0.0.1 when left out)";

[[noreturn]] void bad_address(const std::string& text, const std::string& why) {
  throw Error("--serve", "", std::string(kServeExpected) + "; got '" + text + "'" + why);
}

bool serve_host_is_valid(const std::string& host, bool ipv6) {
  unsigned char address[16];
  if (ipv6) return inet_pton(AF_INET6, host.c_str(), address) == 1;
  return host == "localhost" || inet_pton(AF_INET, host.c_str(), address) == 1;
}

}  // namespace

ServeAddress parse_serve_address(const std::string& text) {
  ServeAddress address;
  std::string port = text;
  if (!text.empty() && text.front() == '[') {
    const std::size_t close = text.find(']');
    if (close == std::string::npos || close + 1 >= text.size() || text[close + 1] != ':')
      bad_address(text, " (a bracketed IPv6 address needs :PORT after it)");
    address.host = text.substr(1, close - 1);
    port = text.substr(close + 2);
    if (!serve_host_is_valid(address.host, true))
      bad_address(text, " ('" + address.host + "' is no IPv6 address)");
  } else if (const std::size_t colon = text.rfind(':'); colon != std::string::npos) {
    address.host = text.substr(0, colon);
    port = text.substr(colon + 1);
    if (address.host.empty()) bad_address(text, " (an empty HOST: leave out the colon too)");
    if (!serve_host_is_valid(address.host, false))
      bad_address(text, " ('" + address.host + "' is no IPv4 address or localhost)");
  }
  const bool digits =
      !port.empty() && port.size() <= 5 &&
      std::all_of(port.begin(), port.end(), [](char c) { return c >= '0' && c <= '9'; });
  if (!digits || std::stoul(port) > 65535)
    bad_address(text, port.empty() ? " (no PORT)" : " (PORT '" + port + "')");
  address.port = static_cast<std::uint16_t>(std::stoul(port));
  return address;
}

const std::vector<ServeOptionSpec>& serve_option_specs() {
  static const std::vector<ServeOptionSpec> specs = {
      {"serve", &S::address,
       "Show it in a browser: serve the viewer page at [HOST:]PORT (HOST 127.0.0.1 unless given; "
       "port 0: any free port; the URL is printed)",
       [](const S& o) -> std::string {
         try {
           parse_serve_address(o.address);
           return "";
         } catch (const Error& e) {
           return e.problem();
         }
       }},
      {"serve-rate", &S::rate_mbit,
       "Cap each viewer's bandwidth, Mbit/s (0: none): how a narrow link feels",
       [](const S& o) { return check_number(o.rate_mbit, 0, 1e6); }},
      {"exit-after", &S::exit_after,
       "Stop serving this many seconds after the result is ready (0: at Ctrl-C)",
       [](const S& o) { return check_number(o.exit_after, 0, 1e9); }},
      {"max-viewers", &S::max_viewers, "Browsers connected at once",
       [](const S& o) { return check_number(static_cast<double>(o.max_viewers), 1, 256); }},
  };
  return specs;
}

void validate(const ServeOptions& options) {
  for (const ServeOptionSpec& spec : serve_option_specs()) {
    if (std::string(spec.name) == "serve" && !options.enabled()) continue;
    const std::string problem = spec.check(options);
    if (!problem.empty()) throw Error(std::string("--") + spec.name, "", problem);
  }
}

}  // namespace meshflow::options
