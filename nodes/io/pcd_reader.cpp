#include "nodes/io/pcd_reader.h"

#include <lzf.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <optional>

#include "nodes/io/binary_value.h"
#include "nodes/io/parse_util.h"
#include "runtime/error.h"

namespace meshflow::io {
namespace {

enum class PcdData { kAscii, kBinary, kBinaryCompressed };

constexpr std::size_t kMaxCount = std::size_t{1} << 16;  // values per field (descriptors: hundreds)
constexpr std::uint64_t kLzfMaxRatio = 88;  // an LZF back-reference: 3 bytes for up to 264

struct PcdField {
  std::string name;
  std::size_t size = 4;
  char type = 'F';
  std::size_t count = 1;
  std::size_t offset = 0;            // bytes from the start of a binary row
  std::optional<ScalarType> scalar;  // nullopt for types meshflow cannot decode (e.g. 64-bit ints)
};

struct PcdHeader {
  std::vector<PcdField> fields;
  std::uint64_t width = 0, height = 1, points = 0;
  PcdData data = PcdData::kAscii;
  std::size_t row_bytes = 0;
  std::size_t values_per_row = 0;
  int lines = 0;
  Eigen::Vector3d viewpoint = Eigen::Vector3d::Zero();  // VIEWPOINT's translation, metres
};

std::optional<ScalarType> pcd_scalar(char type, std::size_t size) {
  if (type == 'F' && size == 4) return ScalarType::kFloat32;
  if (type == 'F' && size == 8) return ScalarType::kFloat64;
  if (type == 'I' && size == 1) return ScalarType::kInt8;
  if (type == 'I' && size == 2) return ScalarType::kInt16;
  if (type == 'I' && size == 4) return ScalarType::kInt32;
  if (type == 'U' && size == 1) return ScalarType::kUint8;
  if (type == 'U' && size == 2) return ScalarType::kUint16;
  if (type == 'U' && size == 4) return ScalarType::kUint32;
  return std::nullopt;
}

// SIZE, TYPE and COUNT as listed, before they are checked against FIELDS.
struct PcdFieldLists {
  std::vector<std::size_t> sizes, counts;
  std::vector<char> types;
  bool have_points = false;  // a POINTS line was read
};

// VIEWPOINT tx ty tz qw qx qy qz: the sensor's position (the rotation is not used).
Eigen::Vector3d parse_viewpoint(const std::vector<std::string_view>& tok, const std::string& path,
                                int line, const std::string& where) {
  if (tok.size() != 8) throw Error(path, where, "VIEWPOINT needs 7 numbers (tx ty tz qw qx qy qz)");
  Eigen::Vector3d viewpoint;
  for (int axis = 0; axis < 3; ++axis)
    viewpoint[axis] = parse_finite(tok[static_cast<std::size_t>(axis) + 1], path,
                                   static_cast<std::size_t>(line), "VIEWPOINT");
  check_position(viewpoint, path, where, "VIEWPOINT");
  return viewpoint;
}

PcdData parse_data_kind(std::string_view kind, const std::string& path, const std::string& where) {
  if (kind == "ascii") return PcdData::kAscii;
  if (kind == "binary") return PcdData::kBinary;
  if (kind == "binary_compressed") return PcdData::kBinaryCompressed;
  throw Error(path, where, "unknown DATA type '" + std::string(kind) + "'");
}

// Reads one header entry (tok[0] its keyword) into `h` and `lists`. Returns true at the DATA
// line, the header's last.
bool parse_header_entry(const std::vector<std::string_view>& tok, const std::string& path,
                        const std::string& where, PcdHeader& h, PcdFieldLists& lists) {
  const std::string_view key = tok[0];
  if (key == "VERSION") return false;
  if (key == "VIEWPOINT") {
    h.viewpoint = parse_viewpoint(tok, path, h.lines, where);
  } else if (key == "FIELDS" || key == "COLUMNS") {
    for (std::size_t i = 1; i < tok.size(); ++i) {
      PcdField f;
      f.name = std::string(tok[i]);
      h.fields.push_back(f);
    }
  } else if (key == "SIZE") {
    for (std::size_t i = 1; i < tok.size(); ++i)
      lists.sizes.push_back(parse_count(tok[i], path, where, "SIZE"));
  } else if (key == "TYPE") {
    for (std::size_t i = 1; i < tok.size(); ++i) {
      if (tok[i].size() != 1 || std::string_view("FIU").find(tok[i][0]) == std::string_view::npos)
        throw Error(path, where, "unknown TYPE '" + std::string(tok[i]) + "' (expected F, I or U)");
      lists.types.push_back(tok[i][0]);
    }
  } else if (key == "COUNT") {
    for (std::size_t i = 1; i < tok.size(); ++i)
      lists.counts.push_back(parse_count(tok[i], path, where, "COUNT"));
  } else if (key == "WIDTH" && tok.size() == 2) {
    h.width = parse_count(tok[1], path, where, "WIDTH");
  } else if (key == "HEIGHT" && tok.size() == 2) {
    h.height = parse_count(tok[1], path, where, "HEIGHT");
  } else if (key == "POINTS" && tok.size() == 2) {
    h.points = parse_count(tok[1], path, where, "POINTS");
    lists.have_points = true;
  } else if (key == "DATA" && tok.size() == 2) {
    h.data = parse_data_kind(tok[1], path, where);
    return true;
  } else {
    throw Error(path, where, "unknown or malformed header entry '" + std::string(key) + "'");
  }
  return false;
}

// FIELDS, SIZE, TYPE and COUNT agree in length; WIDTH x HEIGHT = POINTS (POINTS defaults to it).
void check_header_counts(PcdHeader& h, const PcdFieldLists& lists, const std::string& path) {
  const std::size_t n = h.fields.size();
  if (n == 0) throw Error(path, "header", "no FIELDS line");
  if (lists.sizes.size() != n || lists.types.size() != n)
    throw Error(path, "header", "FIELDS, SIZE and TYPE must list the same number of entries");
  if (!lists.counts.empty() && lists.counts.size() != n)
    throw Error(path, "header", "COUNT must list one entry per field");
  if (h.height != 0 && h.width > std::numeric_limits<std::uint64_t>::max() / h.height)
    throw Error(path, "header", "WIDTH x HEIGHT overflows");
  if (!lists.have_points) h.points = h.width * h.height;
  if (h.width * h.height != h.points)
    throw Error(path, "header",
                "WIDTH x HEIGHT = " + std::to_string(h.width * h.height) +
                    " but POINTS = " + std::to_string(h.points));
}

// Each field's size, type, count and offset in a binary row; the row's size and value count.
void lay_out_fields(PcdHeader& h, const PcdFieldLists& lists, const std::string& path) {
  for (std::size_t i = 0; i < h.fields.size(); ++i) {
    PcdField& f = h.fields[i];
    f.size = lists.sizes[i];
    f.type = lists.types[i];
    f.count = lists.counts.empty() ? 1 : lists.counts[i];
    f.scalar = pcd_scalar(f.type, f.size);
    if (f.size == 0 || f.size > 8)
      throw Error(path, "header",
                  "field '" + f.name + "' has invalid SIZE " + std::to_string(f.size));
    if (f.count == 0 || f.count > kMaxCount)
      throw Error(path, "header",
                  "field '" + f.name + "' has invalid COUNT " + std::to_string(f.count) +
                      " (expected 1 to " + std::to_string(kMaxCount) + ")");
    f.offset = h.row_bytes;
    h.row_bytes += f.size * f.count;
    h.values_per_row += f.count;
  }
}

PcdHeader parse_pcd_header(std::istream& in, const std::string& path) {
  PcdHeader h;
  PcdFieldLists lists;
  std::string line;
  std::vector<std::string_view> tok;
  for (bool have_data = false; !have_data;) {
    const std::string where = "header line " + std::to_string(h.lines + 1);
    if (!read_line(in, line)) throw Error(path, where, "file ends before the DATA line");
    ++h.lines;
    split_whitespace(line, tok);
    if (tok.empty() || tok[0].front() == '#') continue;
    have_data = parse_header_entry(tok, path, where, h, lists);
  }
  check_header_counts(h, lists, path);
  lay_out_fields(h, lists, path);
  return h;
}

// Which field feeds which attribute; an index into header.fields or -1.
struct PcdLayout {
  int x = -1, y = -1, z = -1, nx = -1, ny = -1, nz = -1, rgb = -1, intensity = -1;

  PcdLayout(const PcdHeader& h, const std::string& path) {
    for (std::size_t i = 0; i < h.fields.size(); ++i) {
      const std::string& name = h.fields[i].name;
      int* slot = name == "x"                         ? &x
                  : name == "y"                       ? &y
                  : name == "z"                       ? &z
                  : name == "normal_x"                ? &nx
                  : name == "normal_y"                ? &ny
                  : name == "normal_z"                ? &nz
                  : (name == "rgb" || name == "rgba") ? &rgb
                  : name == "intensity"               ? &intensity
                                                      : nullptr;
      if (slot == nullptr) continue;
      if (!h.fields[i].scalar) {
        throw Error(path, "header", "field '" + name + "' has an unsupported TYPE/SIZE");
      }
      *slot = static_cast<int>(i);
    }
    if (x < 0 || y < 0 || z < 0) throw Error(path, "header", "fields x, y and z are required");
    const int normal_fields = (nx >= 0) + (ny >= 0) + (nz >= 0);
    if (normal_fields != 0 && normal_fields != 3)
      throw Error(path, "header",
                  "only some of the fields normal_x, normal_y, normal_z (" +
                      std::to_string(normal_fields) + " of 3); a normal needs all three");
    if (rgb >= 0 && h.fields[static_cast<std::size_t>(rgb)].size != 4) {
      throw Error(path, "header", "field 'rgb' must have SIZE 4");
    }
  }
  bool normals() const { return nx >= 0 && ny >= 0 && nz >= 0; }
};

// Accessor over one decoded point: value(field) and packed colour bits.
struct PointSink {
  const PcdHeader& h;
  const PcdLayout& layout;
  PointCloud& cloud;
  const std::string& path;

  template <typename Value, typename Bits>
  void add(std::uint64_t index, Value value, Bits bits) {
    const Eigen::Vector3d p(value(layout.x), value(layout.y), value(layout.z));
    check_coordinates(p, path, "point", index);
    cloud.positions.push_back(p.cast<float>());
    if (layout.normals()) {
      cloud.normals.emplace_back(static_cast<float>(value(layout.nx)),
                                 static_cast<float>(value(layout.ny)),
                                 static_cast<float>(value(layout.nz)));
    }
    if (layout.rgb >= 0) {
      const std::uint32_t c = bits(layout.rgb);
      cloud.colors.push_back(Rgb8{static_cast<std::uint8_t>(c >> 16),
                                  static_cast<std::uint8_t>(c >> 8), static_cast<std::uint8_t>(c)});
    }
    if (layout.intensity >= 0)
      cloud.intensities.push_back(static_cast<float>(value(layout.intensity)));
  }
};

void read_ascii(std::istream& in, const PcdHeader& h, PointSink& sink) {
  std::string line;
  std::vector<std::string_view> tok;
  // Token index of the first value of each field.
  std::vector<std::size_t> first(h.fields.size());
  for (std::size_t i = 0, t = 0; i < h.fields.size(); t += h.fields[i].count, ++i) first[i] = t;
  int line_no = h.lines;
  for (std::uint64_t i = 0; i < h.points; ++i) {
    do {
      if (!read_line(in, line)) {
        throw Error(sink.path, "point " + std::to_string(i),
                    "file ends early (POINTS declares " + std::to_string(h.points) + ")");
      }
      ++line_no;
      split_whitespace(line, tok);
    } while (tok.empty());
    const std::string loc = "line " + std::to_string(line_no);
    if (tok.size() != h.values_per_row) {
      throw Error(sink.path, loc,
                  "expected " + std::to_string(h.values_per_row) + " values, found " +
                      std::to_string(tok.size()));
    }
    auto value = [&](int f) {
      const auto fi = static_cast<std::size_t>(f);
      return parse_number(tok[first[fi]], sink.path, loc, h.fields[fi].name);
    };
    auto bits = [&](int f) -> std::uint32_t {
      const auto fi = static_cast<std::size_t>(f);
      if (h.fields[fi].type == 'F') {
        const auto v = static_cast<float>(value(f));
        std::uint32_t b;
        std::memcpy(&b, &v, 4);
        return b;
      }
      return static_cast<std::uint32_t>(
          parse_count(tok[first[fi]], sink.path, loc, h.fields[fi].name));
    };
    sink.add(i, value, bits);
  }
}

// Bytes of the file after the stream's position.
std::uint64_t bytes_left(std::istream& in, const std::string& path) {
  const auto at = in.tellg();
  const std::uint64_t size = file_size(path);
  return at < 0 || static_cast<std::uint64_t>(at) > size ? 0
                                                         : size - static_cast<std::uint64_t>(at);
}

void read_binary(std::istream& in, const PcdHeader& h, PointSink& sink) {
  // The rows must fit in the file before any is read: a lying header must not make the reader
  // allocate for it.
  const std::uint64_t left = bytes_left(in, sink.path);
  if (h.points > left / h.row_bytes) {
    throw Error(sink.path, "DATA binary",
                "file ends early: POINTS declares " + std::to_string(h.points) + " rows of " +
                    std::to_string(h.row_bytes) + " bytes, " + std::to_string(left) +
                    " bytes follow the header");
  }
  constexpr std::uint64_t kChunk = 16384;
  std::vector<unsigned char> buffer;
  for (std::uint64_t i = 0; i < h.points;) {
    const std::uint64_t rows = std::min(kChunk, h.points - i);
    buffer.resize(rows * h.row_bytes);
    in.read(reinterpret_cast<char*>(buffer.data()), static_cast<std::streamsize>(buffer.size()));
    if (static_cast<std::size_t>(in.gcount()) != buffer.size()) {
      throw Error(
          sink.path,
          "point " + std::to_string(i + static_cast<std::uint64_t>(in.gcount()) / h.row_bytes),
          "file ends early: POINTS declares " + std::to_string(h.points) + " rows of " +
              std::to_string(h.row_bytes) + " bytes");
    }
    for (std::uint64_t r = 0; r < rows; ++r) {
      const unsigned char* row = buffer.data() + r * h.row_bytes;
      auto at = [&](int f) { return row + h.fields[static_cast<std::size_t>(f)].offset; };
      sink.add(
          i + r,
          [&](int f) {
            return decode_scalar(at(f), *h.fields[static_cast<std::size_t>(f)].scalar, false);
          },
          [&](int f) { return decode_bits32(at(f), false); });
    }
    i += rows;
  }
}

void read_compressed(std::istream& in, const PcdHeader& h, PointSink& sink) {
  unsigned char sizes[8];
  in.read(reinterpret_cast<char*>(sizes), 8);
  if (in.gcount() != 8)
    throw Error(sink.path, "binary_compressed block", "file ends before the block sizes");
  const std::uint32_t compressed = decode_bits32(sizes, false);
  const std::uint32_t uncompressed = decode_bits32(sizes + 4, false);
  // Both sizes are checked before anything is allocated for them.
  const std::uint64_t left = bytes_left(in, sink.path);
  if (compressed > left) {
    throw Error(sink.path, "binary_compressed block",
                "file ends early: the block declares " + std::to_string(compressed) + " bytes, " +
                    std::to_string(left) + " follow");
  }
  if (uncompressed > kLzfMaxRatio * compressed) {
    throw Error(sink.path, "binary_compressed block",
                "uncompressed size " + std::to_string(uncompressed) + " cannot come from " +
                    std::to_string(compressed) + " LZF bytes");
  }
  if (h.points > uncompressed / h.row_bytes || uncompressed != h.points * h.row_bytes) {
    throw Error(sink.path, "binary_compressed block",
                "uncompressed size " + std::to_string(uncompressed) +
                    " does not match POINTS x row size = " + std::to_string(h.points) + " x " +
                    std::to_string(h.row_bytes));
  }
  std::vector<unsigned char> packed(compressed);
  in.read(reinterpret_cast<char*>(packed.data()), compressed);
  if (static_cast<std::uint32_t>(in.gcount()) != compressed) {
    throw Error(sink.path, "binary_compressed block",
                "file ends early: the block declares " + std::to_string(compressed) + " bytes");
  }
  std::vector<unsigned char> data(uncompressed);
  if (uncompressed > 0 &&
      lzf_decompress(packed.data(), compressed, data.data(), uncompressed) != uncompressed) {
    throw Error(sink.path, "binary_compressed block", "LZF data is corrupt");
  }
  // Field-major layout: all values of field 0, then field 1, ...
  std::vector<std::size_t> base(h.fields.size());
  for (std::size_t f = 0; f < h.fields.size(); ++f) base[f] = h.fields[f].offset * h.points;
  for (std::uint64_t i = 0; i < h.points; ++i) {
    auto at = [&](int f) {
      const auto fi = static_cast<std::size_t>(f);
      return data.data() + base[fi] + i * h.fields[fi].size * h.fields[fi].count;
    };
    sink.add(
        i,
        [&](int f) {
          return decode_scalar(at(f), *h.fields[static_cast<std::size_t>(f)].scalar, false);
        },
        [&](int f) { return decode_bits32(at(f), false); });
  }
}

}  // namespace

PointCloud read_pcd(const std::string& path) {
  std::ifstream in = open_input(path);
  const PcdHeader header = parse_pcd_header(in, path);
  const PcdLayout layout(header, path);
  PointCloud cloud;
  const std::uint64_t plausible = file_size(path) / 3 + 1;  // lying headers must not exhaust memory
  const auto reserve = static_cast<std::size_t>(std::min(header.points, plausible));
  cloud.positions.reserve(reserve);
  if (layout.normals()) cloud.normals.reserve(reserve);
  if (layout.rgb >= 0) cloud.colors.reserve(reserve);
  if (layout.intensity >= 0) cloud.intensities.reserve(reserve);
  PointSink sink{header, layout, cloud, path};
  switch (header.data) {
    case PcdData::kAscii:
      read_ascii(in, header, sink);
      break;
    case PcdData::kBinary:
      read_binary(in, header, sink);
      break;
    case PcdData::kBinaryCompressed:
      read_compressed(in, header, sink);
      break;
  }
  // PCL writes VIEWPOINT 0 0 0 ... when it knows no sensor: only a non-zero position is one.
  if (!header.viewpoint.isZero()) {
    cloud.sensor_origin = header.viewpoint.cast<float>();
    cloud.has_sensor_origin = true;
  }
  if (header.height > 1) {
    cloud.width = static_cast<std::uint32_t>(header.width);
    cloud.height = static_cast<std::uint32_t>(header.height);
    // An organized cloud is a depth camera's image, in the camera's frame unless VIEWPOINT says
    // otherwise: its sensor is at the origin. Recorded so that it survives the filter, which
    // drops the invalid pixels and with them the grid.
    cloud.has_sensor_origin = true;
  }
  return cloud;
}

}  // namespace meshflow::io
