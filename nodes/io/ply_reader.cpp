#include "nodes/io/ply_reader.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <optional>

#include "nodes/io/binary_value.h"
#include "nodes/io/parse_util.h"
#include "runtime/error.h"

namespace meshflow::io {
namespace {

enum class PlyFormat { kAscii, kBinaryLittle, kBinaryBig };

struct PlyProperty {
  std::string name;
  ScalarType type = ScalarType::kFloat32;
  bool is_list = false;
  ScalarType count_type = ScalarType::kUint8;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
  bool has_lists() const {
    return std::any_of(properties.begin(), properties.end(),
                       [](const PlyProperty& p) { return p.is_list; });
  }
  std::size_t row_bytes() const {  // only meaningful without lists
    std::size_t n = 0;
    for (const auto& p : properties) n += scalar_size(p.type);
    return n;
  }
};

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElement> elements;
};

std::optional<ScalarType> parse_ply_type(std::string_view s) {
  static const std::pair<std::string_view, ScalarType> kTypes[] = {
      {"char", ScalarType::kInt8},      {"int8", ScalarType::kInt8},
      {"uchar", ScalarType::kUint8},    {"uint8", ScalarType::kUint8},
      {"short", ScalarType::kInt16},    {"int16", ScalarType::kInt16},
      {"ushort", ScalarType::kUint16},  {"uint16", ScalarType::kUint16},
      {"int", ScalarType::kInt32},      {"int32", ScalarType::kInt32},
      {"uint", ScalarType::kUint32},    {"uint32", ScalarType::kUint32},
      {"float", ScalarType::kFloat32},  {"float32", ScalarType::kFloat32},
      {"double", ScalarType::kFloat64}, {"float64", ScalarType::kFloat64}};
  for (const auto& [name, type] : kTypes) {
    if (name == s) return type;
  }
  return std::nullopt;
}

PlyHeader parse_ply_header(std::istream& in, const std::string& path) {
  std::string line;
  std::vector<std::string_view> tok;
  if (!read_line(in, line) || line != "ply") {
    throw Error(path, "line 1", "not a PLY file (expected the magic line 'ply')");
  }
  PlyHeader header;
  bool have_format = false;
  for (int line_no = 2;; ++line_no) {
    const std::string where = "header line " + std::to_string(line_no);
    if (!read_line(in, line)) throw Error(path, where, "file ends before 'end_header'");
    split_whitespace(line, tok);
    if (tok.empty() || tok[0] == "comment" || tok[0] == "obj_info") continue;
    if (tok[0] == "end_header") break;
    if (tok[0] == "format") {
      if (tok.size() != 3) throw Error(path, where, "expected 'format TYPE 1.0'");
      if (tok[1] == "ascii")
        header.format = PlyFormat::kAscii;
      else if (tok[1] == "binary_little_endian")
        header.format = PlyFormat::kBinaryLittle;
      else if (tok[1] == "binary_big_endian")
        header.format = PlyFormat::kBinaryBig;
      else
        throw Error(path, where, "unknown format '" + std::string(tok[1]) + "'");
      have_format = true;
    } else if (tok[0] == "element") {
      if (tok.size() != 3) throw Error(path, where, "expected 'element NAME COUNT'");
      header.elements.push_back(
          PlyElement{std::string(tok[1]), parse_count(tok[2], path, where, "element count"), {}});
    } else if (tok[0] == "property") {
      if (header.elements.empty()) throw Error(path, where, "property before any element");
      PlyProperty prop;
      if (tok.size() == 5 && tok[1] == "list") {
        const auto count_type = parse_ply_type(tok[2]);
        const auto item_type = parse_ply_type(tok[3]);
        if (!count_type || !item_type) {
          throw Error(path, where,
                      "unknown list property types '" + std::string(tok[2]) + " " +
                          std::string(tok[3]) + "'");
        }
        prop = PlyProperty{std::string(tok[4]), *item_type, true, *count_type};
      } else if (tok.size() == 3) {
        const auto type = parse_ply_type(tok[1]);
        if (!type) {
          throw Error(path, where, "unknown property type '" + std::string(tok[1]) + "'");
        }
        prop = PlyProperty{std::string(tok[2]), *type, false, ScalarType::kUint8};
      } else {
        throw Error(path, where, "expected 'property TYPE NAME' or 'property list T T NAME'");
      }
      header.elements.back().properties.push_back(prop);
    } else {
      throw Error(path, where, "unknown header keyword '" + std::string(tok[0]) + "'");
    }
  }
  if (!have_format) throw Error(path, "header", "missing 'format' line");
  // Rows without properties hold no bytes: a binary element of 10^18 of them would be "read"
  // for ever without consuming the file (found by fuzz_ply).
  for (const PlyElement& e : header.elements) {
    if (e.properties.empty() && e.count > 0) {
      throw Error(path, "element '" + e.name + "'",
                  "declares " + std::to_string(e.count) + " rows but no properties");
    }
  }
  return header;
}

// Which property feeds which field of the cloud (-1 = absent).
struct FieldMap {
  enum Slot { kX, kY, kZ, kNx, kNy, kNz, kR, kG, kB, kI, kSlots };
  std::array<int, kSlots> prop{};
  bool color_is_float = false;
  double color_scale = 1.0;

  explicit FieldMap(const PlyElement& e) {
    prop.fill(-1);
    static const std::array<std::vector<std::string_view>, kSlots> kNames = {
        {{"x"},
         {"y"},
         {"z"},
         {"nx", "normal_x"},
         {"ny", "normal_y"},
         {"nz", "normal_z"},
         {"red", "r", "diffuse_red"},
         {"green", "g", "diffuse_green"},
         {"blue", "b", "diffuse_blue"},
         {"intensity", "scalar_intensity", "reflectance"}}};
    for (int s = 0; s < kSlots; ++s) {
      for (std::size_t i = 0; i < e.properties.size(); ++i) {
        const auto& names = kNames[static_cast<std::size_t>(s)];
        if (!e.properties[i].is_list &&
            std::find(names.begin(), names.end(), e.properties[i].name) != names.end()) {
          prop[static_cast<std::size_t>(s)] = static_cast<int>(i);
          break;
        }
      }
    }
    if (has_colors()) {
      const ScalarType t = e.properties[static_cast<std::size_t>(prop[kR])].type;
      color_is_float = t == ScalarType::kFloat32 || t == ScalarType::kFloat64;
      color_scale = color_is_float ? 255.0 : (t == ScalarType::kUint16 ? 1.0 / 257.0 : 1.0);
    }
  }
  bool has_normals() const { return prop[kNx] >= 0 && prop[kNy] >= 0 && prop[kNz] >= 0; }
  /// Throws when some but not all of nx, ny, nz are present: half a normal is no normal, and
  /// dropping it silently would hide that the file is not what its writer meant.
  void check_normals(const std::string& path) const {
    const int present = (prop[kNx] >= 0) + (prop[kNy] >= 0) + (prop[kNz] >= 0);
    if (present != 0 && present != 3)
      throw Error(path, "header",
                  "element 'vertex' has only some of the normal properties nx, ny, nz (" +
                      std::to_string(present) + " of 3); a normal needs all three");
  }
  bool has_colors() const { return prop[kR] >= 0 && prop[kG] >= 0 && prop[kB] >= 0; }
  bool has_intensity() const { return prop[kI] >= 0; }
};

std::uint8_t to_color(double v, double scale) {
  return static_cast<std::uint8_t>(std::clamp(std::lround(v * scale), 0L, 255L));
}

// Appends one vertex from its property values (indexed like the element's properties).
void append_vertex(const std::vector<double>& values, const FieldMap& map, PointCloud& cloud,
                   const std::string& path, std::uint64_t row) {
  auto value = [&](int slot) { return values[static_cast<std::size_t>(map.prop[slot])]; };
  const Eigen::Vector3d p(value(FieldMap::kX), value(FieldMap::kY), value(FieldMap::kZ));
  if (row == 0) {  // map coordinates (UTM, in doubles) get a local frame, +z up
    cloud.origin = local_origin_near(p);
    cloud.z_up = is_map_frame(cloud.origin);
  }
  cloud.positions.push_back(local_position(p, cloud.origin, path, "vertex", row));
  if (map.has_normals()) {
    cloud.normals.emplace_back(static_cast<float>(value(FieldMap::kNx)),
                               static_cast<float>(value(FieldMap::kNy)),
                               static_cast<float>(value(FieldMap::kNz)));
  }
  if (map.has_colors()) {
    cloud.colors.push_back(Rgb8{to_color(value(FieldMap::kR), map.color_scale),
                                to_color(value(FieldMap::kG), map.color_scale),
                                to_color(value(FieldMap::kB), map.color_scale)});
  }
  if (map.has_intensity()) cloud.intensities.push_back(static_cast<float>(value(FieldMap::kI)));
}

class ElementReader {
 public:
  ElementReader(std::istream& in, const std::string& path, PlyFormat format)
      : in_(in), path_(path), format_(format) {}

  // Reads (or skips) every row of `e`; calls sink(values, row) for each row if given.
  template <typename Sink>
  void read(const PlyElement& e, Sink&& sink) {
    std::vector<double> values(e.properties.size());
    if (format_ == PlyFormat::kAscii) {
      read_ascii(e, values, sink);
    } else if (!e.has_lists()) {
      read_binary_fixed(e, values, sink);
    } else {
      read_binary_lists(e, values, sink);
    }
  }

  int line() const { return line_; }
  /// While on, the items of the row's last list property are kept (list()) instead of skipped.
  void collect_lists(bool on) { collect_lists_ = on; }
  const std::vector<double>& list() const { return list_; }

 private:
  std::string where(const PlyElement& e, std::uint64_t row) const {
    return e.name + " " + std::to_string(row) + " of " + std::to_string(e.count);
  }

  template <typename Sink>
  void read_ascii(const PlyElement& e, std::vector<double>& values, Sink& sink) {
    std::string text;
    std::vector<std::string_view> tok;
    for (std::uint64_t row = 0; row < e.count; ++row) {
      do {
        if (!read_line(in_, text)) {
          throw Error(path_, where(e, row),
                      "file ends early (the header declares " + std::to_string(e.count) + ")");
        }
        ++line_;
        split_whitespace(text, tok);
      } while (tok.empty());
      const std::string loc = "line " + std::to_string(line_);
      std::size_t t = 0;
      for (std::size_t i = 0; i < e.properties.size(); ++i) {
        const PlyProperty& p = e.properties[i];
        if (t >= tok.size()) throw Error(path_, loc, "missing value for property '" + p.name + "'");
        if (p.is_list) {
          const std::uint64_t n = parse_count(tok[t++], path_, loc, p.name);
          if (tok.size() - t < n) throw Error(path_, loc, "list '" + p.name + "' is short");
          if (collect_lists_) {
            list_.clear();
            for (std::uint64_t j = 0; j < n; ++j)
              list_.push_back(parse_number(tok[t + j], path_, loc, p.name));
          }
          t += n;
          values[i] = static_cast<double>(n);
        } else {
          values[i] = parse_number(tok[t++], path_, loc, p.name);
        }
      }
      if (t != tok.size()) {
        throw Error(
            path_, loc,
            "expected " + std::to_string(t) + " values, found " + std::to_string(tok.size()));
      }
      sink(values, row);
    }
  }

  template <typename Sink>
  void read_binary_fixed(const PlyElement& e, std::vector<double>& values, Sink& sink) {
    const std::size_t row_bytes = e.row_bytes();
    const bool swap = format_ == PlyFormat::kBinaryBig;
    constexpr std::uint64_t kRowsPerChunk = 16384;
    std::vector<unsigned char> buffer;
    for (std::uint64_t row = 0; row < e.count;) {
      const std::uint64_t rows = std::min(kRowsPerChunk, e.count - row);
      buffer.resize(rows * row_bytes);
      in_.read(reinterpret_cast<char*>(buffer.data()), static_cast<std::streamsize>(buffer.size()));
      const auto got = static_cast<std::uint64_t>(in_.gcount());
      if (got != buffer.size()) {
        throw Error(path_, where(e, row + got / row_bytes),
                    "file ends early: the header declares " + std::to_string(e.count) +
                        " rows of " + std::to_string(row_bytes) + " bytes");
      }
      for (std::uint64_t r = 0; r < rows; ++r) {
        const unsigned char* p = buffer.data() + r * row_bytes;
        for (std::size_t i = 0; i < e.properties.size(); ++i) {
          values[i] = decode_scalar(p, e.properties[i].type, swap);
          p += scalar_size(e.properties[i].type);
        }
        sink(values, row + r);
      }
      row += rows;
    }
  }

  template <typename Sink>
  void read_binary_lists(const PlyElement& e, std::vector<double>& values, Sink& sink) {
    const bool swap = format_ == PlyFormat::kBinaryBig;
    unsigned char buf[8];
    for (std::uint64_t row = 0; row < e.count; ++row) {
      for (std::size_t i = 0; i < e.properties.size(); ++i) {
        const PlyProperty& p = e.properties[i];
        if (p.is_list) {
          read_exact(buf, scalar_size(p.count_type), e, row);
          const double n = decode_scalar(buf, p.count_type, swap);
          if (n < 0) throw Error(path_, where(e, row), "negative list length in '" + p.name + "'");
          if (collect_lists_) {
            list_.clear();
            for (double j = 0; j < n; ++j) {
              read_exact(buf, scalar_size(p.type), e, row);
              list_.push_back(decode_scalar(buf, p.type, swap));
            }
          } else {
            const auto skip =
                static_cast<std::streamsize>(n) * static_cast<std::streamsize>(scalar_size(p.type));
            in_.ignore(skip);
            if (in_.gcount() != skip)
              throw Error(path_, where(e, row), "file ends inside list '" + p.name + "'");
          }
          values[i] = n;
        } else {
          read_exact(buf, scalar_size(p.type), e, row);
          values[i] = decode_scalar(buf, p.type, swap);
        }
      }
      sink(values, row);
    }
  }

  void read_exact(unsigned char* buf, std::size_t n, const PlyElement& e, std::uint64_t row) {
    in_.read(reinterpret_cast<char*>(buf), static_cast<std::streamsize>(n));
    if (static_cast<std::size_t>(in_.gcount()) != n) {
      throw Error(path_, where(e, row),
                  "file ends early (the header declares " + std::to_string(e.count) + ")");
    }
  }

  std::istream& in_;
  const std::string& path_;
  PlyFormat format_;
  int line_ = 0;
  bool collect_lists_ = false;
  std::vector<double> list_;
};

}  // namespace

namespace {

// Reads the vertex element into `cloud` and, when `triangles` is given, the face element's
// vertex index lists (polygons fan-triangulated) into it. With `flush`, hands `cloud` to it
// (and empties it) each time it holds `batch` points, and once more with the rest.
void read_ply_elements(const std::string& path, PointCloud& cloud, std::vector<Triangle>* triangles,
                       std::size_t batch = 0,
                       const std::function<void(const PointCloud&)>* flush = nullptr) {
  std::ifstream in = open_input(path);
  const PlyHeader header = parse_ply_header(in, path);
  const auto vertex_it = std::find_if(header.elements.begin(), header.elements.end(),
                                      [](const PlyElement& e) { return e.name == "vertex"; });
  if (vertex_it == header.elements.end()) throw Error(path, "header", "no 'vertex' element");
  const FieldMap map(*vertex_it);
  map.check_normals(path);
  for (int s : {FieldMap::kX, FieldMap::kY, FieldMap::kZ}) {
    if (map.prop[static_cast<std::size_t>(s)] < 0) {
      throw Error(path, "header", std::string("vertex element lacks property '") + "xyz"[s] + "'");
    }
  }
  const auto face_it = std::find_if(header.elements.begin(), header.elements.end(),
                                    [](const PlyElement& e) { return e.name == "face"; });
  if (triangles && face_it != header.elements.end()) {
    const auto& props = face_it->properties;
    if (props.empty() || !props.back().is_list ||
        (props.back().name != "vertex_indices" && props.back().name != "vertex_index")) {
      throw Error(path, "header",
                  "the face element's last property must be the list 'vertex_indices'");
    }
  }

  // Never trust the declared count for allocation: a lying header must not exhaust memory.
  const std::uint64_t plausible = file_size(path) / 3 + 1;
  std::size_t reserve = static_cast<std::size_t>(std::min(vertex_it->count, plausible));
  if (flush) reserve = std::min(reserve, batch);
  cloud.positions.reserve(reserve);
  if (map.has_normals()) cloud.normals.reserve(reserve);
  if (map.has_colors()) cloud.colors.reserve(reserve);
  if (map.has_intensity()) cloud.intensities.reserve(reserve);

  const auto hand_over = [&] {
    (*flush)(cloud);
    cloud.positions.clear();
    cloud.normals.clear();
    cloud.colors.clear();
    cloud.intensities.clear();
  };
  ElementReader reader(in, path, header.format);
  for (const PlyElement& e : header.elements) {
    if (&e == &*vertex_it) {
      reader.read(e, [&](const std::vector<double>& v, std::uint64_t row) {
        append_vertex(v, map, cloud, path, row);
        if (flush && cloud.size() >= batch) hand_over();
      });
      if (flush && !cloud.empty()) hand_over();
    } else if (triangles && face_it != header.elements.end() && &e == &*face_it) {
      reader.collect_lists(true);
      reader.read(e, [&](const std::vector<double>&, std::uint64_t row) {
        const std::vector<double>& ids = reader.list();
        const std::string where = "face " + std::to_string(row);
        if (ids.size() < 3) throw Error(path, where, "a face needs at least 3 vertex indices");
        for (double id : ids) {
          if (!(id >= 0.0) || id >= static_cast<double>(vertex_it->count) || id != std::floor(id)) {
            throw Error(path, where,
                        "vertex index " + std::to_string(id) + " is not in [0, " +
                            std::to_string(vertex_it->count) + ")");
          }
        }
        for (std::size_t k = 2; k < ids.size(); ++k)
          triangles->push_back({static_cast<std::uint32_t>(ids[0]),
                                static_cast<std::uint32_t>(ids[k - 1]),
                                static_cast<std::uint32_t>(ids[k])});
      });
      reader.collect_lists(false);
    } else {
      reader.read(e, [](const std::vector<double>&, std::uint64_t) {});
    }
  }
  // Anything but whitespace after the last element means the header's counts are wrong.
  char c;
  while (in.get(c)) {
    if (header.format != PlyFormat::kAscii || !std::isspace(static_cast<unsigned char>(c))) {
      throw Error(path, "after the last element",
                  "unexpected extra data: the header's element counts do not match the file");
    }
  }
}

// The vertex element, its field map, and the byte where its rows start (fixed-size rows before
// it), or why its rows cannot be read by byte range.
struct PlyVertexPlace {
  PlyHeader header;
  std::size_t vertex = 0;  // element index
  std::uint64_t start = 0;
  std::string why_not;
};

PlyVertexPlace place_vertex_rows(std::ifstream& in, const std::string& path) {
  PlyVertexPlace place;
  place.header = parse_ply_header(in, path);
  const auto& elements = place.header.elements;
  const auto it = std::find_if(elements.begin(), elements.end(),
                               [](const PlyElement& e) { return e.name == "vertex"; });
  if (it == elements.end()) throw Error(path, "header", "no 'vertex' element");
  place.vertex = static_cast<std::size_t>(it - elements.begin());
  place.start = static_cast<std::uint64_t>(in.tellg());
  if (place.header.format == PlyFormat::kAscii) {
    place.why_not =
        "ASCII PLY: rows have no fixed size, so a row's byte is known only by "
        "reading every line before it";
    return place;
  }
  for (std::size_t e = 0; e <= place.vertex; ++e) {
    if (elements[e].has_lists()) {
      place.why_not =
          "element '" + elements[e].name + "' has list properties: its rows have no fixed size";
      return place;
    }
    if (e < place.vertex) place.start += elements[e].count * elements[e].row_bytes();
  }
  return place;
}

}  // namespace

PlyVertexRows ply_vertex_rows(const std::string& path) {
  std::ifstream in = open_input(path);
  const PlyVertexPlace place = place_vertex_rows(in, path);
  PlyVertexRows rows;
  rows.count = place.header.elements[place.vertex].count;
  rows.by_byte_range = place.why_not.empty();
  rows.why_not = place.why_not;
  return rows;
}

void read_ply_vertex_range(const std::string& path, std::uint64_t first, std::uint64_t count,
                           std::size_t batch, const std::function<void(const PointCloud&)>& sink) {
  std::ifstream in = open_input(path);
  const PlyVertexPlace place = place_vertex_rows(in, path);
  if (!place.why_not.empty()) throw Error(path, "byte ranges", place.why_not);
  const PlyElement& e = place.header.elements[place.vertex];
  const FieldMap map(e);
  map.check_normals(path);
  for (int s : {FieldMap::kX, FieldMap::kY, FieldMap::kZ})
    if (map.prop[static_cast<std::size_t>(s)] < 0)
      throw Error(path, "header", std::string("vertex element lacks property '") + "xyz"[s] + "'");
  if (first > e.count || count > e.count - first)
    throw Error(path, "vertex " + std::to_string(first) + " + " + std::to_string(count),
                "range past the " + std::to_string(e.count) + " vertices the header declares");
  const std::size_t row_bytes = e.row_bytes();
  if (file_size(path) < place.start + e.count * row_bytes)
    throw Error(path, "vertex rows",
                "file ends early: the header declares " + std::to_string(e.count) + " rows of " +
                    std::to_string(row_bytes) + " bytes");
  const bool swap = place.header.format == PlyFormat::kBinaryBig;
  std::vector<double> values(e.properties.size());
  const auto decode = [&](const unsigned char* p) {
    for (std::size_t i = 0; i < e.properties.size(); ++i) {
      values[i] = decode_scalar(p, e.properties[i].type, swap);
      p += scalar_size(e.properties[i].type);
    }
  };
  std::vector<unsigned char> buffer(row_bytes);
  const auto read_rows = [&](std::uint64_t row, std::uint64_t rows) {
    buffer.resize(static_cast<std::size_t>(rows) * row_bytes);
    in.seekg(static_cast<std::streamoff>(place.start + row * row_bytes));
    in.read(reinterpret_cast<char*>(buffer.data()), static_cast<std::streamsize>(buffer.size()));
    if (static_cast<std::size_t>(in.gcount()) != buffer.size())
      throw Error(path, "vertex " + std::to_string(row), "cannot read the row's bytes");
  };
  PointCloud cloud;
  if (count == 0) return;
  read_rows(0, 1);  // the first vertex sets the local frame, as in read_ply()
  decode(buffer.data());
  append_vertex(values, map, cloud, path, 0);
  const Eigen::Vector3d origin = cloud.origin;
  const bool z_up = cloud.z_up;
  const std::size_t size = std::max<std::size_t>(batch, 1);
  cloud = PointCloud{};
  cloud.origin = origin;
  cloud.z_up = z_up;
  const auto hand_over = [&] {
    sink(cloud);
    cloud.positions.clear();
    cloud.normals.clear();
    cloud.colors.clear();
    cloud.intensities.clear();
  };
  constexpr std::uint64_t kRowsPerRead = 16384;
  for (std::uint64_t row = first; row < first + count;) {
    const std::uint64_t rows = std::min(kRowsPerRead, first + count - row);
    read_rows(row, rows);
    for (std::uint64_t r = 0; r < rows; ++r) {
      decode(buffer.data() + r * row_bytes);
      append_vertex(values, map, cloud, path, row + r);
      if (cloud.size() >= size) hand_over();
    }
    row += rows;
  }
  if (!cloud.empty()) hand_over();
}

PointCloud read_ply(const std::string& path) {
  PointCloud cloud;
  read_ply_elements(path, cloud, nullptr);
  return cloud;
}

void read_ply_batches(const std::string& path, std::size_t batch,
                      const std::function<void(const PointCloud&)>& sink) {
  PointCloud cloud;
  const std::size_t size = std::max<std::size_t>(batch, 1);
  read_ply_elements(path, cloud, nullptr, size, &sink);
}

bool ply_has_faces(const std::string& path) {
  std::ifstream in = open_input(path);
  const PlyHeader header = parse_ply_header(in, path);
  return std::any_of(header.elements.begin(), header.elements.end(),
                     [](const PlyElement& e) { return e.name == "face" && e.count > 0; });
}

TriangleMesh read_ply_mesh(const std::string& path) {
  PointCloud cloud;
  TriangleMesh mesh;
  read_ply_elements(path, cloud, &mesh.triangles);
  mesh.vertices = std::move(cloud.positions);
  // A mesh has no local frame: world coordinates, as floats, which hold them to a few mm within
  // 1e6 m; farther out (a UTM northing: 0.5 m steps) the mesh is refused, as before.
  if (!cloud.origin.isZero())
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
      const Eigen::Vector3d world = mesh.vertices[i].cast<double>() + cloud.origin;
      check_coordinates(world, path, "vertex", i);
      mesh.vertices[i] = world.cast<float>();
    }
  mesh.normals = std::move(cloud.normals);
  mesh.colors = std::move(cloud.colors);
  return mesh;
}

}  // namespace meshflow::io
