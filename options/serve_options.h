#pragma once
// The serving options of the option model: where and how a front end (the `meshflow` CLI's
// --serve on run, live, reconstruct and view; the Python module's serve()) shows meshes in a
// browser, in one table with each option's name, help and check. Front ends register the rows
// and validate values here, so a bad address is refused the same way with the same message
// everywhere, when the options are parsed and before any input is read. No front-end or
// network type appears here (the server itself is serve/server.h).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <variant>
#include <vector>

namespace meshflow::options {

/// The serving settings, as a user gives them.
struct ServeOptions {
  std::string address;      ///< [HOST:]PORT (parse_serve_address); empty: no server
  double rate_mbit = 0.0;   ///< per-viewer bandwidth cap, Mbit/s (0: none)
  double exit_after = 0.0;  ///< seconds of serving once the result is ready (0: until Ctrl-C)
  std::size_t max_viewers = 8;
  bool enabled() const { return !address.empty(); }
};

/// A parsed --serve address.
struct ServeAddress {
  std::string host = "127.0.0.1";  ///< an IPv4 or IPv6 address (no brackets) or "localhost"
  std::uint16_t port = 0;          ///< 0: any free port
};

/// Parses `[HOST:]PORT`: PORT a whole number in [0, 65535] (0: any free port), HOST an IPv4
/// address, "localhost" or a bracketed IPv6 address ("[::1]:8080"); without HOST the loopback
/// interface 127.0.0.1 (safe by default). Throws meshflow::Error("--serve", "", what was
/// expected and what was given) for anything else: an empty text, an empty host (":8080"), a
/// host name other than localhost, a port that is no number or out of range. O(length).
ServeAddress parse_serve_address(const std::string& text);

/// A field of ServeOptions, by type.
using ServeOptionField =
    std::variant<std::string ServeOptions::*, double ServeOptions::*, std::size_t ServeOptions::*>;

/// One row of the serving options' table.
struct ServeOptionSpec {
  const char* name;  ///< as the CLI spells it without "--": "serve-rate"
  ServeOptionField field;
  const char* help;
  /// "" when the field's value in `options` is valid, else what was expected and what was
  /// given, without the option's name.
  std::function<std::string(const ServeOptions& options)> check;
};

/// The table: serve (the address), serve-rate, exit-after, max-viewers. Thread-safe (a constant).
const std::vector<ServeOptionSpec>& serve_option_specs();

/// Throws meshflow::Error("--NAME", "", problem) for the first option of `options` that fails
/// its check; the address is checked only when a server is asked for (enabled()). O(options).
void validate(const ServeOptions& options);

}  // namespace meshflow::options
