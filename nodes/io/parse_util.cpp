#include "nodes/io/parse_util.h"

#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "runtime/error.h"

namespace meshflow::io {

void split_whitespace(std::string_view line, std::vector<std::string_view>& tokens) {
  tokens.clear();
  std::size_t i = 0;
  const std::size_t n = line.size();
  while (i < n) {
    while (i < n && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const std::size_t start = i;
    while (i < n && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
}

double parse_number(std::string_view token, const std::string& source, const std::string& location,
                    std::string_view field) {
  std::string_view t = token;
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  double value = 0.0;
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
  if (ec == std::errc::result_out_of_range) {
    throw Error(source, location,
                "field '" + std::string(field) + "': value '" + std::string(token) +
                    "' is out of the range of a double");
  }
  if (ec != std::errc() || end != t.data() + t.size() || t.empty()) {
    throw Error(
        source, location,
        "field '" + std::string(field) + "': expected a number, got '" + std::string(token) + "'");
  }
  return value;
}

double parse_number(std::string_view token, const std::string& source, std::size_t line,
                    std::string_view field) {
  std::string_view t = token;
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  double value = 0.0;
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
  if (ec == std::errc() && end == t.data() + t.size() && !t.empty()) return value;
  return parse_number(token, source, "line " + std::to_string(line), field);  // throws
}

double parse_finite(std::string_view token, const std::string& source, std::size_t line,
                    std::string_view field) {
  const double value = parse_number(token, source, line, field);
  if (!std::isfinite(value))
    throw Error(source, "line " + std::to_string(line),
                "field '" + std::string(field) + "': expected a finite number, got '" +
                    std::string(token) + "'");
  return value;
}

std::uint64_t parse_count(std::string_view token, const std::string& source,
                          const std::string& location, std::string_view field) {
  std::uint64_t value = 0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec != std::errc() || end != token.data() + token.size() || token.empty()) {
    throw Error(source, location,
                "field '" + std::string(field) + "': expected a non-negative integer, got '" +
                    std::string(token) + "'");
  }
  return value;
}

void check_coordinates(const Eigen::Vector3d& p, const std::string& source,
                       const std::string& location) {
  for (int i = 0; i < 3; ++i) {
    if (std::isfinite(p[i]) && std::abs(p[i]) > kMaxAbsCoordinate) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%g", p[i]);
      throw Error(source, location,
                  std::string("coordinate ") + "xyz"[i] + " = " + buf +
                      " is beyond +-1e6 m: corrupt data or wrong units");
    }
  }
}

void check_coordinates(const Eigen::Vector3d& p, const std::string& source, std::size_t line) {
  check_coordinates(p, source, "line", line);
}

void check_coordinates(const Eigen::Vector3d& p, const std::string& source, std::string_view what,
                       std::uint64_t index) {
  if ((p.array().abs() > kMaxAbsCoordinate).any())
    check_coordinates(p, source, std::string(what) + " " + std::to_string(index));
}

void check_position(const Eigen::Vector3d& p, const std::string& source,
                    const std::string& location, std::string_view what) {
  if (p.allFinite() && (p.array().abs() <= kMaxAbsCoordinate).all()) return;
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%g, %g, %g)", p.x(), p.y(), p.z());
  throw Error(source, location,
              std::string(what) + " " + buf +
                  " is not finite or beyond +-1e6 m: corrupt data or wrong units");
}

Eigen::Vector3d local_origin_near(const Eigen::Vector3d& p) {
  constexpr double kGeoreferencedBeyond = 1e4;  // metres; float ulp there: 1 mm
  if (!p.allFinite() || (p.array().abs() <= kGeoreferencedBeyond).all() ||
      (p.array().abs() > 1e8).any())  // (no map coordinate: local_position() refuses it)
    return Eigen::Vector3d::Zero();
  return ((p / 1000.0).array().round() * 1000.0 + 0.0).matrix();  // + 0.0: no "-0" origin
}

bool is_map_frame(const Eigen::Vector3d& origin) {
  return origin.z() == 0.0 && (origin.x() != 0.0 || origin.y() != 0.0);
}

Eigen::Vector3f local_position(const Eigen::Vector3d& p, const Eigen::Vector3d& origin,
                               const std::string& source, std::string_view what,
                               std::uint64_t index) {
  const Eigen::Vector3d local = p - origin;
  // Map coordinates reach 1e7 m (UTM northings; eastings with a zone prefix under 1e8): past
  // that a number is no position on Earth, first point or not.
  constexpr double kMaxGeoreferenced = 1e8;
  // Fast path (every point of a good file): one comparison per coordinate (NaN fails them).
  if ((local.array().abs() <= kMaxAbsCoordinate).all() &&
      (p.array().abs() <= kMaxGeoreferenced).all())
    return local.cast<float>();
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(p[i])) continue;
    char where[160] = "";
    if (std::abs(p[i]) > kMaxGeoreferenced ||
        (origin.isZero() && std::abs(p[i]) > kMaxAbsCoordinate))
      std::snprintf(where, sizeof where, "coordinate %c = %g is beyond +-%g m", "xyz"[i], p[i],
                    origin.isZero() ? kMaxAbsCoordinate : kMaxGeoreferenced);
    else if (std::abs(local[i]) > kMaxAbsCoordinate)
      std::snprintf(where, sizeof where,
                    "(%.3f, %.3f, %.3f) lies more than 1e6 m from the first point", p.x(), p.y(),
                    p.z());
    if (where[0] != '\0')
      throw Error(source, std::string(what) + " " + std::to_string(index),
                  std::string(where) +
                      ": corrupt data, wrong units or a cloud too large for one "
                      "local frame");
  }
  return local.cast<float>();
}

std::ifstream open_input(const std::string& path) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (std::filesystem::is_directory(status)) throw Error(path, "", "is a directory, not a file");
  // A FIFO would block the reader until something writes to it; devices and sockets have no
  // size. meshflow reads files whose size it knows.
  if (std::filesystem::is_fifo(status))
    throw Error(path, "", "is a FIFO (named pipe), not a regular file");
  if (std::filesystem::is_socket(status) || std::filesystem::is_block_file(status) ||
      std::filesystem::is_character_file(status))
    throw Error(path, "", "is a socket or device, not a regular file");
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path, "", "cannot open file for reading: " + errno_text());
  return in;
}

std::string errno_text() {
  if (errno == 0) return "unknown reason";
  return std::strerror(errno);
}

std::uint64_t file_size(const std::string& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  return ec ? 0 : static_cast<std::uint64_t>(size);
}

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

bool read_line(std::istream& in, std::string& line) {
  if (!std::getline(in, line)) return false;
  while (!line.empty() && (line.back() == '\r' || line.back() == '\n')) line.pop_back();
  return true;
}

}  // namespace meshflow::io
