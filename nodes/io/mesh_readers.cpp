#include "nodes/io/mesh_readers.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "nodes/io/glb_reader.h"
#include "nodes/io/parse_util.h"
#include "nodes/io/ply_reader.h"
#include "nodes/io/text_chunks.h"
#include "runtime/error.h"

namespace meshflow::io {
namespace {

// Walks the lines of a text file with their 1-based numbers.
class LineCursor {
 public:
  explicit LineCursor(std::string_view text) : text_(text) {}
  bool next(std::string_view& line) {
    if (at_ >= text_.size()) return false;
    const std::size_t end = std::min(text_.find('\n', at_), text_.size());
    line = text_.substr(at_, end - at_);
    at_ = end + 1;
    ++number_;
    return true;
  }
  std::size_t number() const { return number_; }

 private:
  std::string_view text_;
  std::size_t at_ = 0, number_ = 0;
};

// A vertex position from three tokens: finite and within +-1e6 m, or an error naming the line.
Eigen::Vector3f parse_position(const std::string_view* tokens, const std::string& path,
                               std::size_t line) {
  const Eigen::Vector3d p(parse_finite(tokens[0], path, line, "x"),
                          parse_finite(tokens[1], path, line, "y"),
                          parse_finite(tokens[2], path, line, "z"));
  check_coordinates(p, path, line);
  return p.cast<float>();
}

// Colour channels as 0..1 floats or 0..255 integers, decided for the whole file afterwards.
Rgb8 to_rgb8(const Eigen::Vector3f& c, float scale) {
  const auto channel = [scale](float v) {
    return static_cast<std::uint8_t>(std::clamp(std::lround(v * scale), 0L, 255L));
  };
  return {channel(c.x()), channel(c.y()), channel(c.z())};
}

void fan_triangulate(const std::vector<std::uint32_t>& polygon, std::vector<Triangle>& out) {
  for (std::size_t k = 2; k < polygon.size(); ++k)
    out.push_back({polygon[0], polygon[k - 1], polygon[k]});
}

// Resolves an OBJ index (1-based, or negative: relative to the end) against `count` elements.
std::uint32_t obj_index(std::string_view token, std::size_t count, const std::string& path,
                        std::size_t line, const char* what) {
  const double v = parse_number(token, path, line, what);
  const double resolved = v < 0 ? static_cast<double>(count) + v : v - 1;
  if (v == 0 || v != std::floor(v) || resolved < 0 || resolved >= static_cast<double>(count)) {
    throw Error(path, "line " + std::to_string(line),
                std::string(what) + " index " + std::string(token) + " is not in 1.." +
                    std::to_string(count) + " (or -1..-" + std::to_string(count) + ")");
  }
  return static_cast<std::uint32_t>(resolved);
}

float colour_scale(const std::vector<Eigen::Vector3f>& colours) {
  float largest = 0.0f;
  for (const Eigen::Vector3f& c : colours) largest = std::max(largest, c.maxCoeff());
  return largest > 1.0f ? 1.0f : 255.0f;
}

}  // namespace

TriangleMesh read_obj_mesh(const std::string& path) {
  const std::string text = read_whole_file(path);
  TriangleMesh mesh;
  std::vector<Eigen::Vector3f> normals, colours;
  bool normals_match = true;  // every corner names normal i for vertex i
  std::vector<std::string_view> tokens;
  std::vector<std::uint32_t> polygon;
  LineCursor lines(text);
  std::string_view line;
  while (lines.next(line)) {
    const std::size_t n = lines.number();
    split_whitespace(line, tokens);
    if (tokens.empty() || tokens[0].front() == '#') continue;
    if (tokens[0] == "v") {
      if (tokens.size() < 4) throw Error(path, "line " + std::to_string(n), "'v' needs x y z");
      mesh.vertices.push_back(parse_position(&tokens[1], path, n));
      if (tokens.size() >= 7) {
        colours.emplace_back(static_cast<float>(parse_finite(tokens[4], path, n, "red")),
                             static_cast<float>(parse_finite(tokens[5], path, n, "green")),
                             static_cast<float>(parse_finite(tokens[6], path, n, "blue")));
      }
    } else if (tokens[0] == "vn") {
      if (tokens.size() < 4) throw Error(path, "line " + std::to_string(n), "'vn' needs 3 values");
      normals.emplace_back(static_cast<float>(parse_number(tokens[1], path, n, "nx")),
                           static_cast<float>(parse_number(tokens[2], path, n, "ny")),
                           static_cast<float>(parse_number(tokens[3], path, n, "nz")));
    } else if (tokens[0] == "f") {
      if (tokens.size() < 4)
        throw Error(path, "line " + std::to_string(n), "a face needs at least 3 corners");
      polygon.clear();
      for (std::size_t k = 1; k < tokens.size(); ++k) {
        const std::string_view corner = tokens[k];
        const std::size_t slash = corner.find('/');
        const std::uint32_t v =
            obj_index(corner.substr(0, slash), mesh.vertices.size(), path, n, "vertex");
        const std::size_t second =
            slash == std::string_view::npos ? std::string_view::npos : corner.find('/', slash + 1);
        if (second == std::string_view::npos || second + 1 >= corner.size()) {
          normals_match = false;
        } else {
          normals_match = normals_match && obj_index(corner.substr(second + 1), normals.size(),
                                                     path, n, "normal") == v;
        }
        polygon.push_back(v);
      }
      fan_triangulate(polygon, mesh.triangles);
    }
  }
  if (normals_match && normals.size() == mesh.vertices.size() && !mesh.triangles.empty())
    mesh.normals = std::move(normals);
  if (colours.size() == mesh.vertices.size() && !colours.empty()) {
    const float scale = colour_scale(colours);
    for (const Eigen::Vector3f& c : colours) mesh.colors.push_back(to_rgb8(c, scale));
  }
  return mesh;
}

TriangleMesh read_off_mesh(const std::string& path) {
  const std::string text = read_whole_file(path);
  LineCursor lines(text);
  std::vector<std::string_view> tokens;
  // Lines with content: comments and blank lines skipped.
  const auto next_tokens = [&](const char* expected) {
    std::string_view line;
    while (lines.next(line)) {
      split_whitespace(line.substr(0, line.find('#')), tokens);
      if (!tokens.empty()) return;
    }
    throw Error(path, "line " + std::to_string(lines.number()),
                std::string("the file ends early: expected ") + expected);
  };
  next_tokens("the OFF keyword");
  const std::string_view keyword = tokens[0];
  const bool has_normals = keyword.find('N') != std::string_view::npos;
  const bool has_colours = keyword.find('C') != std::string_view::npos;
  if (keyword.size() < 3 || keyword.substr(keyword.size() - 3) != "OFF" || keyword.size() > 5)
    throw Error(path, "line 1",
                "expected OFF, COFF, NOFF or CNOFF, got '" + std::string(keyword) + "'");
  if (tokens.size() == 1)
    next_tokens("the vertex and face counts");
  else
    tokens.erase(tokens.begin());
  if (tokens.size() < 2)
    throw Error(path, "line " + std::to_string(lines.number()),
                "expected the vertex and face counts");
  const std::string where = "line " + std::to_string(lines.number());
  const std::uint64_t vertex_count = parse_count(tokens[0], path, where, "vertex count");
  const std::uint64_t face_count = parse_count(tokens[1], path, where, "face count");
  // Each vertex needs at least "0 0 0\n" and each face "3 0 0 0\n".
  if (vertex_count * 6 + face_count * 8 > text.size() || vertex_count > 0xFFFFFFFFull) {
    throw Error(path, where,
                "the header claims " + std::to_string(vertex_count) + " vertices and " +
                    std::to_string(face_count) + " faces, more than the file's " +
                    std::to_string(text.size()) + " bytes can hold");
  }
  TriangleMesh mesh;
  mesh.vertices.reserve(vertex_count);
  std::vector<Eigen::Vector3f> colours;
  const std::size_t columns = 3 + (has_normals ? 3 : 0) + (has_colours ? 3 : 0);
  for (std::uint64_t i = 0; i < vertex_count; ++i) {
    next_tokens("a vertex");
    const std::size_t n = lines.number();
    if (tokens.size() < columns)
      throw Error(path, "line " + std::to_string(n),
                  "a vertex needs " + std::to_string(columns) + " values, got " +
                      std::to_string(tokens.size()));
    mesh.vertices.push_back(parse_position(&tokens[0], path, n));
    std::size_t at = 3;
    if (has_normals) {
      mesh.normals.emplace_back(static_cast<float>(parse_number(tokens[3], path, n, "nx")),
                                static_cast<float>(parse_number(tokens[4], path, n, "ny")),
                                static_cast<float>(parse_number(tokens[5], path, n, "nz")));
      at = 6;
    }
    if (has_colours) {
      colours.emplace_back(static_cast<float>(parse_finite(tokens[at], path, n, "red")),
                           static_cast<float>(parse_finite(tokens[at + 1], path, n, "green")),
                           static_cast<float>(parse_finite(tokens[at + 2], path, n, "blue")));
    }
  }
  std::vector<std::uint32_t> polygon;
  for (std::uint64_t f = 0; f < face_count; ++f) {
    next_tokens("a face");
    const std::size_t n = lines.number();
    const std::uint64_t corners =
        parse_count(tokens[0], path, "line " + std::to_string(n), "corner count");
    if (corners < 3 || corners + 1 > tokens.size())
      throw Error(path, "line " + std::to_string(n),
                  "a face needs a corner count of at least 3 followed by that many indices");
    polygon.clear();
    for (std::uint64_t k = 1; k <= corners; ++k) {
      const std::uint64_t v =
          parse_count(tokens[k], path, "line " + std::to_string(n), "vertex index");
      if (v >= vertex_count)
        throw Error(path, "line " + std::to_string(n),
                    "vertex index " + std::to_string(v) + " is not in [0, " +
                        std::to_string(vertex_count) + ")");
      polygon.push_back(static_cast<std::uint32_t>(v));
    }
    fan_triangulate(polygon, mesh.triangles);
  }
  if (!colours.empty()) {
    const float scale = colour_scale(colours);
    for (const Eigen::Vector3f& c : colours) mesh.colors.push_back(to_rgb8(c, scale));
  }
  return mesh;
}

namespace {

// Gives corners at bit-identical positions one vertex index, in order of first appearance.
class VertexWelder {
 public:
  explicit VertexWelder(TriangleMesh& mesh) : mesh_(mesh) {}
  std::uint32_t index(const Eigen::Vector3f& p) {
    Key key{};
    for (int k = 0; k < 3; ++k) {
      const float v = p[k] == 0.0f ? 0.0f : p[k];  // -0 and +0 are one position
      std::memcpy(&key[static_cast<std::size_t>(k)], &v, sizeof v);
    }
    const auto [it, inserted] =
        ids_.emplace(key, static_cast<std::uint32_t>(mesh_.vertices.size()));
    if (inserted) mesh_.vertices.push_back(p);
    return it->second;
  }

 private:
  using Key = std::array<std::uint32_t, 3>;
  struct KeyHash {
    std::size_t operator()(const Key& k) const {
      std::uint64_t h = k[0] * 0x9E3779B97F4A7C15ull;
      h ^= (h >> 29) + k[1] * 0xBF58476D1CE4E5B9ull;
      h ^= (h >> 31) + k[2] * 0x94D049BB133111EBull;
      return static_cast<std::size_t>(h ^ (h >> 32));
    }
  };
  TriangleMesh& mesh_;
  std::unordered_map<Key, std::uint32_t, KeyHash> ids_;
};

void check_stl_corner(const Eigen::Vector3f& p, const std::string& path, std::uint64_t triangle) {
  if (!p.allFinite())
    throw Error(path, "triangle " + std::to_string(triangle),
                "a corner is not finite (NaN or Inf)");
  check_coordinates(p.cast<double>(), path, "triangle", triangle);
}

TriangleMesh read_binary_stl(const std::string& text, const std::string& path,
                             std::uint32_t count) {
  TriangleMesh mesh;
  VertexWelder weld(mesh);
  mesh.triangles.reserve(count);
  const char* at = text.data() + 84;
  for (std::uint32_t t = 0; t < count; ++t, at += 50) {
    Triangle tri{};
    for (int c = 0; c < 3; ++c) {
      float xyz[3];
      std::memcpy(xyz, at + 12 + 12 * c, sizeof xyz);
      const Eigen::Vector3f p(xyz[0], xyz[1], xyz[2]);
      check_stl_corner(p, path, t);
      tri[static_cast<std::size_t>(c)] = weld.index(p);
    }
    mesh.triangles.push_back(tri);
  }
  return mesh;
}

TriangleMesh read_ascii_stl(const std::string& text, const std::string& path) {
  TriangleMesh mesh;
  VertexWelder weld(mesh);
  LineCursor lines(text);
  std::vector<std::string_view> tokens;
  std::string_view line;
  std::vector<std::uint32_t> facet;
  bool in_facet = false;
  while (lines.next(line)) {
    const std::size_t n = lines.number();
    split_whitespace(line, tokens);
    if (tokens.empty()) continue;
    if (tokens[0] == "facet") {
      in_facet = true;
      facet.clear();
    } else if (tokens[0] == "vertex") {
      if (!in_facet || tokens.size() < 4)
        throw Error(path, "line " + std::to_string(n), "expected 'vertex x y z' inside a facet");
      facet.push_back(weld.index(parse_position(&tokens[1], path, n)));
    } else if (tokens[0] == "endfacet") {
      if (facet.size() != 3)
        throw Error(path, "line " + std::to_string(n),
                    "a facet has " + std::to_string(facet.size()) + " vertices, expected 3");
      mesh.triangles.push_back({facet[0], facet[1], facet[2]});
      in_facet = false;
    }
  }
  if (in_facet)
    throw Error(path, "line " + std::to_string(lines.number()), "the file ends inside a facet");
  return mesh;
}

}  // namespace

TriangleMesh read_stl_mesh(const std::string& path) {
  const std::string text = read_whole_file(path);
  if (text.size() >= 84) {
    std::uint32_t count = 0;
    std::memcpy(&count, text.data() + 80, sizeof count);
    if (84 + 50 * std::uint64_t{count} == text.size()) return read_binary_stl(text, path, count);
  }
  if (text.compare(0, 5, "solid") == 0) return read_ascii_stl(text, path);
  throw Error(path, "",
              "not an STL file: no 'solid' keyword (ASCII) and the size does not match a binary "
              "STL's triangle count (84 + 50 bytes per triangle)");
}

bool is_mesh_file(const std::string& path) {
  const std::string ext = lower_extension(path);
  return ext == ".ply" || ext == ".obj" || ext == ".off" || ext == ".stl" || ext == ".glb";
}

TriangleMesh read_mesh(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext == ".ply") return read_ply_mesh(path);
  if (ext == ".obj") return read_obj_mesh(path);
  if (ext == ".off") return read_off_mesh(path);
  if (ext == ".stl") return read_stl_mesh(path);
  if (ext == ".glb") return read_glb_mesh(path);
  throw Error(path, "", "unknown mesh format '" + ext + "' (reads .ply .obj .off .stl .glb)");
}

}  // namespace meshflow::io
