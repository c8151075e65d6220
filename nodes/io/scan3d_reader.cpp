#include "nodes/io/scan3d_reader.h"

#include <charconv>
#include <cmath>
#include <filesystem>

#include "nodes/io/parse_util.h"
#include "nodes/io/text_chunks.h"
#include "runtime/error.h"
#include "runtime/parallel.h"

namespace meshflow::io {
namespace {

// 3DTK's left-handed (x right, y up, z forward) cm frame to meshflow's right-handed metres:
// x' = z, y' = -x, z' = y (the inverse of 3DTK's .xyz importer).
Eigen::Matrix3d tdtk_to_meshflow() {
  Eigen::Matrix3d m;
  m << 0, 0, 1, -1, 0, 0, 0, 1, 0;
  return m;
}

Eigen::Vector3d read_triple(std::istream& in, const std::string& path, int line_no,
                            const char* what) {
  std::string line;
  std::vector<std::string_view> tok;
  const std::string loc = "line " + std::to_string(line_no);
  if (!read_line(in, line)) throw Error(path, loc, std::string("missing ") + what);
  split_whitespace(line, tok);
  if (tok.size() != 3) throw Error(path, loc, std::string("expected 3 numbers: ") + what);
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i)
    v[i] = parse_number(tok[static_cast<std::size_t>(i)], path, loc, what);
  if (!v.allFinite()) throw Error(path, loc, std::string("non-finite ") + what);
  return v;
}

bool is_three_numbers(const std::vector<std::string_view>& tok) {
  if (tok.size() != 3) return false;
  for (std::string_view t : tok) {
    double v;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (ec != std::errc() || end != t.data() + t.size()) return false;
  }
  return true;
}

}  // namespace

Eigen::Isometry3f read_3dtk_pose(const std::string& path) {
  std::ifstream in = open_input(path);
  const Eigen::Vector3d t_cm = read_triple(in, path, 1, "translation tx ty tz (cm)");
  const Eigen::Vector3d deg = read_triple(in, path, 2, "rotation rx ry rz (degrees)");
  const Eigen::Vector3d rad = deg * (M_PI / 180.0);
  // 3DTK: R = Rx * Ry * Rz, p_world = R * p_scan + t, all in its own frame.
  const Eigen::Matrix3d r = (Eigen::AngleAxisd(rad.x(), Eigen::Vector3d::UnitX()) *
                             Eigen::AngleAxisd(rad.y(), Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(rad.z(), Eigen::Vector3d::UnitZ()))
                                .toRotationMatrix();
  const Eigen::Matrix3d c = tdtk_to_meshflow();
  Eigen::Isometry3d T_world_scan = Eigen::Isometry3d::Identity();
  T_world_scan.linear() = c * r * c.transpose();
  T_world_scan.translation() = c * t_cm * 0.01;
  check_position(T_world_scan.translation(), path, "line 1", "translation");
  return T_world_scan.cast<float>();
}

PointCloud read_3dtk_scan(const std::string& path, const Scan3dOptions& options,
                          const std::string& pose_path) {
  const std::string text = read_whole_file(path);
  std::string resolved_pose = pose_path;
  if (resolved_pose.empty()) {
    resolved_pose = std::filesystem::path(path).replace_extension(".pose").string();
    if (!std::filesystem::exists(resolved_pose)) resolved_pose.clear();
  }
  const Eigen::Isometry3f T_world_scan =
      resolved_pose.empty() ? Eigen::Isometry3f::Identity() : read_3dtk_pose(resolved_pose);
  const Eigen::Matrix3d c = tdtk_to_meshflow();
  const double min2 = options.min_range_cm * options.min_range_cm;
  const double max2 = options.max_range_cm * options.max_range_cm;

  using Points = std::vector<Eigen::Vector3f>;
  const auto parts =
      parse_chunks<Points>(split_into_line_chunks(text), [&](const TextChunk& chunk, Points& out) {
        std::vector<std::string_view> tok;
        std::size_t line_no = chunk.first_line;
        std::size_t start = 0;
        for (; start < chunk.text.size(); ++line_no) {
          std::size_t end = chunk.text.find('\n', start);
          if (end == std::string_view::npos) end = chunk.text.size();
          split_whitespace(chunk.text.substr(start, end - start), tok);
          start = end + 1;
          if (tok.empty()) continue;
          if (line_no == 1 && !is_three_numbers(tok)) continue;  // legacy "360 x 225" header
          if (tok.size() < 3) {
            throw Error(path, "line " + std::to_string(line_no),
                        "expected x y z (cm), found " + std::to_string(tok.size()) + " values");
          }
          const Eigen::Vector3d p_cm(parse_number(tok[0], path, line_no, "x"),
                                     parse_number(tok[1], path, line_no, "y"),
                                     parse_number(tok[2], path, line_no, "z"));
          if (!p_cm.allFinite())
            throw Error(path, "line " + std::to_string(line_no), "non-finite coordinate");
          check_coordinates(p_cm * 0.01, path, line_no);
          const double r2 = p_cm.squaredNorm();
          if (r2 < min2 || r2 >= max2) continue;
          out.push_back(T_world_scan * (c * p_cm * 0.01).cast<float>());
        }
      });
  PointCloud cloud;
  concatenate_parts(parts, cloud.positions);  // the copies in parallel
  cloud.sensor_origin = T_world_scan.translation();
  cloud.has_sensor_origin = true;
  return cloud;
}

}  // namespace meshflow::io
