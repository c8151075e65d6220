#pragma once
// Plain-text point readers: .xyz / .txt / .pts (one point per line).

#include <string>

#include "runtime/point_cloud.h"

namespace meshflow::io {

/// Reads whitespace-separated columns, one point per line. The column count is fixed by the
/// first data line: 3 = x y z; 4 = x y z intensity; 6 = x y z r g b; 7 or more =
/// x y z intensity r g b (further columns ignored). Colours are 0..255. Lines starting with
/// '#' or '//' and empty lines are skipped; a first line holding a single integer (the .pts
/// point count) is checked against the number of points read.
/// Throws meshflow::Error naming the file, line and column on malformed input. O(file size).
PointCloud read_xyz(const std::string& path);

}  // namespace meshflow::io
