#pragma once
// Plain-text point readers: .xyz / .txt / .pts / .asc / .csv (one point per line).

#include <string>

#include "runtime/point_cloud.h"

namespace meshflow::io {

/// Reads one point per line, values separated by whitespace, commas or semicolons. The
/// columns' meaning comes from a header line when the file has one (a first line of names,
/// possibly after '//' as CloudCompare writes it: x y z, nx ny nz / normal_x.., r g b / red
/// green blue, intensity / i / reflectance / scalar_intensity; other names are skipped), else
/// from the column count of the first data line: 3 = x y z; 4 = x y z intensity; 6 = x y z
/// nx ny nz when columns 4-6 of that line are a unit vector with a fractional component, else
/// x y z r g b; 7 or 8 = x y z intensity r g b; 9 = x y z with r g b and nx ny nz in either
/// order (the unit vector decides); 10 or more = x y z intensity r g b nx ny nz. Colours are
/// 0..255. Lines starting with '#' or '//' (other than a header) and empty lines are skipped;
/// a first line holding a single integer (the .pts point count) is checked against the number
/// of points read. `columns` (e.g. "x,y,z,nx,ny,nz,r,g,b" or "x y z skip intensity"; the
/// header names above, and "skip" or "_" for a column to ignore) replaces the header and the
/// detection; a header line is then skipped. Throws meshflow::Error naming the file, line and
/// column on malformed input, or naming --columns for an unknown name or an incomplete triple.
/// Map coordinates (more than 1e4 m out, e.g. a UTM terrain tile) are read relative to a local
/// origin with +z up (PointCloud::origin, z_up). O(file size).
PointCloud read_xyz(const std::string& path, const std::string& columns = "");

}  // namespace meshflow::io
