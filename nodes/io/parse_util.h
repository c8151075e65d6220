#pragma once
// Helpers shared by the text and binary readers: tokenizing, number parsing with precise
// error messages, and coordinate sanity checks.

#include <Eigen/Core>
#include <cstdint>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

namespace meshflow::io {

/// Coordinates beyond this magnitude (metres) are rejected as corrupt data or wrong units.
constexpr double kMaxAbsCoordinate = 1e6;

/// Splits `line` at spaces, tabs and carriage returns into `tokens` (views into `line`).
void split_whitespace(std::string_view line, std::vector<std::string_view>& tokens);

/// Parses a decimal floating-point token ("1.5", "-2e3", "nan", "inf"). Throws meshflow::Error
/// naming `source`, `location` and `field` when the token is not a number or overflows double.
double parse_number(std::string_view token, const std::string& source, const std::string& location,
                    std::string_view field);

/// As above with the location "line N", formatted only when there is an error.
double parse_number(std::string_view token, const std::string& source, std::size_t line,
                    std::string_view field);

/// As parse_number, but NaN and infinities are errors too (timestamps, pose entries).
double parse_finite(std::string_view token, const std::string& source, std::size_t line,
                    std::string_view field);

/// Parses a non-negative integer token; throws meshflow::Error like parse_number.
std::uint64_t parse_count(std::string_view token, const std::string& source,
                          const std::string& location, std::string_view field);

/// Throws meshflow::Error if a finite component of p exceeds kMaxAbsCoordinate.
/// NaN/Inf are allowed here (organized clouds use them); the filter stage removes them.
void check_coordinates(const Eigen::Vector3d& p, const std::string& source,
                       const std::string& location);

/// As above with the location "line N", formatted only when there is an error.
void check_coordinates(const Eigen::Vector3d& p, const std::string& source, std::size_t line);

/// As above with the location "<what> <index>" (e.g. "point 12"), formatted only when there is
/// an error: the per-point check of the binary readers costs a comparison, not a string.
void check_coordinates(const Eigen::Vector3d& p, const std::string& source, std::string_view what,
                       std::uint64_t index);

/// Throws meshflow::Error naming `source`, `location` and `what` unless every component of `p`
/// (metres) is finite and within +-kMaxAbsCoordinate: for a pose's translation or a sensor
/// position, where a non-finite or huge value would silently turn every point into garbage.
void check_position(const Eigen::Vector3d& p, const std::string& source,
                    const std::string& location, std::string_view what);

/// The local frame of a georeferenced cloud whose first point is `p` (world coordinates, metres):
/// zero when every coordinate is within 1e4 m (floats hold those to a millimetre), else `p`
/// rounded to whole kilometres, so nearby tiles share round origins (PointCloud::origin). O(1).
Eigen::Vector3d local_origin_near(const Eigen::Vector3d& p);

/// Whether a local frame `origin` (local_origin_near) is a map's: shifted horizontally only, as
/// projected coordinates (UTM, national grids) are, whose z is a height: +z is up. O(1).
bool is_map_frame(const Eigen::Vector3d& origin);

/// `p` (world coordinates, metres) relative to `origin`, as stored in a PointCloud; throws
/// meshflow::Error naming `source` and "<what> <index>" when a finite coordinate lies more than
/// kMaxAbsCoordinate from the origin (corrupt data, wrong units, or a cloud too large for one
/// local frame) or beyond 1e8 m (no map coordinate is). NaN/Inf pass through (organized clouds
/// use them). O(1).
Eigen::Vector3f local_position(const Eigen::Vector3d& p, const Eigen::Vector3d& origin,
                               const std::string& source, std::string_view what,
                               std::uint64_t index);

/// Opens the regular file `path` for binary reading; throws meshflow::Error naming it when it is
/// missing or unreadable (with the errno text), a directory, a FIFO, a socket or a device.
std::ifstream open_input(const std::string& path);

/// strerror(errno) ("No such file or directory", "Permission denied"), or "unknown reason"
/// when errno is 0: the why of a failed open, for the error message.
std::string errno_text();

/// Size of the file in bytes (0 if unknown).
std::uint64_t file_size(const std::string& path);

/// Lower-cased extension including the dot (".ply"), or "" if none.
std::string lower_extension(const std::string& path);

/// Reads one line without its end-of-line characters; false at end of file.
bool read_line(std::istream& in, std::string& line);

}  // namespace meshflow::io
