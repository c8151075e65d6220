#include "nodes/io/xyz_reader.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "nodes/io/parse_util.h"
#include "runtime/error.h"

namespace meshflow::io {
namespace {
std::uint8_t color_value(double v, const std::string& path, const std::string& loc) {
  if (!(v >= 0.0 && v <= 255.0)) {
    throw Error(path, loc, "colour value " + std::to_string(v) + " is outside 0..255");
  }
  return static_cast<std::uint8_t>(std::lround(v));
}
}  // namespace

PointCloud read_xyz(const std::string& path) {
  std::ifstream in = open_input(path);
  PointCloud cloud;
  std::string line;
  std::vector<std::string_view> tok;
  std::size_t columns = 0;
  std::optional<std::uint64_t> declared;
  static const char* kNames[] = {"x", "y", "z", "intensity", "r", "g", "b"};
  for (int line_no = 1; read_line(in, line); ++line_no) {
    split_whitespace(line, tok);
    if (tok.empty() || tok[0].front() == '#' || tok[0].substr(0, 2) == "//") continue;
    const std::string loc = "line " + std::to_string(line_no);
    if (columns == 0 && cloud.empty() && !declared && tok.size() == 1) {
      declared = parse_count(tok[0], path, loc, "point count");
      continue;
    }
    if (columns == 0) {
      if (tok.size() < 3 || tok.size() == 5) {
        throw Error(path, loc,
                    "expected 3, 4, 6 or 7+ columns (x y z [intensity] [r g b]), found " +
                        std::to_string(tok.size()));
      }
      columns = tok.size();
    } else if (tok.size() != columns) {
      throw Error(path, loc,
                  "expected " + std::to_string(columns) + " columns like the first line, found " +
                      std::to_string(tok.size()));
    }
    double v[7];
    const std::size_t used = std::min<std::size_t>(columns, 7);
    for (std::size_t c = 0; c < used; ++c) {
      // Column meaning depends on the layout: with 6 columns, 3..5 are r g b.
      const std::size_t name = (columns == 6 && c >= 3) ? c + 1 : c;
      v[c] = parse_number(tok[c], path, loc, kNames[name]);
    }
    const Eigen::Vector3d p(v[0], v[1], v[2]);
    check_coordinates(p, path, loc);
    cloud.positions.push_back(p.cast<float>());
    if (columns == 4 || columns >= 7) cloud.intensities.push_back(static_cast<float>(v[3]));
    if (columns >= 6) {
      const std::size_t c0 = columns == 6 ? 3 : 4;
      cloud.colors.push_back(Rgb8{color_value(v[c0], path, loc), color_value(v[c0 + 1], path, loc),
                                  color_value(v[c0 + 2], path, loc)});
    }
  }
  if (declared && *declared != cloud.size()) {
    throw Error(path, "line 1",
                "declares " + std::to_string(*declared) + " points but the file holds " +
                    std::to_string(cloud.size()));
  }
  return cloud;
}

}  // namespace meshflow::io
