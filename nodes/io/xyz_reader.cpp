#include "nodes/io/xyz_reader.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <optional>

#include "nodes/io/parse_util.h"
#include "runtime/error.h"

namespace meshflow::io {
namespace {

enum class Role { kX, kY, kZ, kNx, kNy, kNz, kR, kG, kB, kIntensity, kSkip };

const char* role_name(Role r) {
  static const char* kNames[] = {"x", "y", "z", "nx", "ny", "nz", "r", "g", "b", "intensity", "-"};
  return kNames[static_cast<int>(r)];
}

// Splits at whitespace, commas and semicolons.
void split_fields(std::string_view line, std::vector<std::string_view>& out) {
  out.clear();
  std::size_t i = 0;
  auto separator = [](char c) {
    return c == ',' || c == ';' || std::isspace(static_cast<unsigned char>(c)) != 0;
  };
  while (i < line.size()) {
    while (i < line.size() && separator(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !separator(line[i])) ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
}

bool is_number(std::string_view token) {
  if (token.empty()) return false;
  const char c = token.front();
  return std::isdigit(static_cast<unsigned char>(c)) != 0 || c == '-' || c == '+' || c == '.' ||
         token == "nan" || token == "NaN" || token == "inf";
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

Role role_of_name(std::string_view name) {
  const std::string n = lower(name);
  static const std::pair<const char*, Role> kNames[] = {{"x", Role::kX},
                                                        {"y", Role::kY},
                                                        {"z", Role::kZ},
                                                        {"nx", Role::kNx},
                                                        {"ny", Role::kNy},
                                                        {"nz", Role::kNz},
                                                        {"normal_x", Role::kNx},
                                                        {"normal_y", Role::kNy},
                                                        {"normal_z", Role::kNz},
                                                        {"normalx", Role::kNx},
                                                        {"normaly", Role::kNy},
                                                        {"normalz", Role::kNz},
                                                        {"r", Role::kR},
                                                        {"g", Role::kG},
                                                        {"b", Role::kB},
                                                        {"red", Role::kR},
                                                        {"green", Role::kG},
                                                        {"blue", Role::kB},
                                                        {"intensity", Role::kIntensity},
                                                        {"i", Role::kIntensity},
                                                        {"reflectance", Role::kIntensity},
                                                        {"scalar_intensity", Role::kIntensity}};
  for (const auto& [known, role] : kNames)
    if (n == known) return role;
  return Role::kSkip;
}

// Whether the first data line's columns [first, first + 3) look like a unit normal: each in
// [-1, 1], unit length within 2 %, and not three integers (colours 0 0 1 would pass otherwise).
bool unit_vector_at(const std::vector<std::string_view>& tok, std::size_t first) {
  double v[3];
  bool fractional = false;
  for (int k = 0; k < 3; ++k) {
    const std::string s(tok[first + static_cast<std::size_t>(k)]);
    char* end = nullptr;
    v[k] = std::strtod(s.c_str(), &end);
    if (end == s.c_str() || !(std::abs(v[k]) <= 1.0)) return false;
    fractional = fractional || v[k] != std::round(v[k]);
  }
  return fractional && std::abs(std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) - 1.0) < 0.02;
}

// Roles of the columns of a file without a header, from its first data line.
std::vector<Role> roles_by_count(const std::vector<std::string_view>& tok, const std::string& path,
                                 const std::string& loc) {
  using R = Role;
  const std::size_t n = tok.size();
  if (n < 3 || n == 5)
    throw Error(path, loc,
                "expected 3, 4, 6 or 7+ columns (x y z [intensity] [r g b] [nx ny nz]) or a "
                "header line naming them, found " +
                    std::to_string(n));
  std::vector<Role> roles(n, R::kSkip);
  roles[0] = R::kX;
  roles[1] = R::kY;
  roles[2] = R::kZ;
  auto put = [&roles](std::size_t at, std::array<Role, 3> three) {
    for (std::size_t k = 0; k < 3; ++k) roles[at + k] = three[k];
  };
  const std::array<Role, 3> normal{R::kNx, R::kNy, R::kNz}, colour{R::kR, R::kG, R::kB};
  if (n == 3) {
    return roles;
  } else if (n == 4) {
    roles[3] = R::kIntensity;
  } else if (n == 6) {
    put(3, unit_vector_at(tok, 3) ? normal : colour);
  } else if (n == 9) {
    const bool normal_first = unit_vector_at(tok, 3);
    put(3, normal_first ? normal : colour);
    put(6, normal_first ? colour : normal);
  } else {  // 7, 8 or 10 and more
    roles[3] = R::kIntensity;
    put(4, colour);
    if (n >= 10) put(7, normal);
  }
  return roles;
}

std::uint8_t color_value(double v, const std::string& path, const std::string& loc) {
  if (!(v >= 0.0 && v <= 255.0)) {
    throw Error(path, loc, "colour value " + std::to_string(v) + " is outside 0..255");
  }
  return static_cast<std::uint8_t>(std::lround(v));
}

// Appends the point of one data line.
void append_point(const std::vector<std::string_view>& tok, const std::vector<Role>& roles,
                  const std::string& path, int line_no, const std::string& loc, PointCloud& cloud) {
  double value[10] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  bool has[10] = {false, false, false, false, false, false, false, false, false, false};
  for (std::size_t c = 0; c < roles.size(); ++c) {
    if (roles[c] == Role::kSkip) continue;
    const auto r = static_cast<std::size_t>(roles[c]);
    value[r] = parse_number(tok[c], path, loc, role_name(roles[c]));
    has[r] = true;
  }
  const Eigen::Vector3d p(value[0], value[1], value[2]);
  if (cloud.positions.empty()) {  // map coordinates (UTM tiles) get a local frame, +z up
    cloud.origin = local_origin_near(p);
    cloud.z_up = is_map_frame(cloud.origin);
  }
  cloud.positions.push_back(
      local_position(p, cloud.origin, path, "line", static_cast<std::uint64_t>(line_no)));
  if (has[static_cast<int>(Role::kNx)])
    cloud.normals.emplace_back(static_cast<float>(value[3]), static_cast<float>(value[4]),
                               static_cast<float>(value[5]));
  if (has[static_cast<int>(Role::kR)])
    cloud.colors.push_back(Rgb8{color_value(value[6], path, loc), color_value(value[7], path, loc),
                                color_value(value[8], path, loc)});
  if (has[static_cast<int>(Role::kIntensity)])
    cloud.intensities.push_back(static_cast<float>(value[9]));
}

// Checks that a header names x, y and z and either all or none of each triple.
void check_roles(const std::vector<Role>& roles, const std::string& path, const std::string& loc) {
  auto count = [&roles](std::initializer_list<Role> which) {
    int n = 0;
    for (Role r : which) n += std::count(roles.begin(), roles.end(), r) > 0 ? 1 : 0;
    return n;
  };
  if (count({Role::kX, Role::kY, Role::kZ}) != 3)
    throw Error(path, loc, "the header line does not name the columns x, y and z");
  for (auto triple : {std::initializer_list<Role>{Role::kNx, Role::kNy, Role::kNz},
                      std::initializer_list<Role>{Role::kR, Role::kG, Role::kB}}) {
    const int n = count(triple);
    if (n != 0 && n != 3)
      throw Error(path, loc,
                  "the header line names only some of " + std::string(role_name(*triple.begin())) +
                      " and its two companions; give all three");
  }
}

// The roles of --columns.
std::vector<Role> parse_column_spec(const std::string& columns) {
  std::vector<std::string_view> names;
  split_fields(columns, names);
  std::vector<Role> roles;
  for (std::string_view name : names) {
    const Role role = role_of_name(name);
    if (role == Role::kSkip && name != "skip" && name != "_")
      throw Error("--columns", "'" + std::string(name) + "'",
                  "unknown column: expected x y z nx ny nz r g b intensity (or the names "
                  "normal_x.., red green blue) or skip");
    roles.push_back(role);
  }
  check_roles(roles, "--columns", columns);
  return roles;
}

}  // namespace

PointCloud read_xyz(const std::string& path, const std::string& columns) {
  std::ifstream in = open_input(path);
  PointCloud cloud;
  std::string line;
  std::vector<std::string_view> tok;
  // Empty until the layout is known (a header line, the first data line), unless given.
  std::vector<Role> roles = columns.empty() ? std::vector<Role>{} : parse_column_spec(columns);
  const bool given = !roles.empty();
  std::optional<std::uint64_t> declared;
  for (int line_no = 1; read_line(in, line); ++line_no) {
    std::string_view text(line);
    const bool slashes = text.substr(0, 2) == "//";
    if (slashes) text.remove_prefix(2);
    split_fields(text, tok);
    if (tok.empty() || tok[0].front() == '#') continue;
    const std::string loc = "line " + std::to_string(line_no);
    if (given && cloud.empty() && !is_number(tok[0])) continue;  // a header --columns replaces
    if (roles.empty() && cloud.empty() && !is_number(tok[0])) {  // a header line of names
      roles.resize(tok.size());
      std::transform(tok.begin(), tok.end(), roles.begin(), role_of_name);
      check_roles(roles, path, loc);
      continue;
    }
    if (slashes) continue;  // a comment
    if (cloud.empty() && !declared && tok.size() == 1 && (roles.empty() || roles.size() > 1)) {
      declared = parse_count(tok[0], path, loc, "point count");
      continue;
    }
    if (roles.empty()) roles = roles_by_count(tok, path, loc);
    if (tok.size() != roles.size()) {
      throw Error(path, loc,
                  "expected " + std::to_string(roles.size()) + " columns like " +
                      (given ? "--columns" : "the first line") + ", found " +
                      std::to_string(tok.size()));
    }
    append_point(tok, roles, path, line_no, loc, cloud);
  }
  if (declared && *declared != cloud.size()) {
    throw Error(path, "line 1",
                "declares " + std::to_string(*declared) + " points but the file holds " +
                    std::to_string(cloud.size()));
  }
  return cloud;
}

}  // namespace meshflow::io
