#include "nodes/io/las_reader.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <vector>

#include "nodes/io/parse_util.h"
#include "runtime/error.h"

namespace meshflow::io {
namespace {

template <typename T>
T field(const unsigned char* at) {
  T value;
  std::memcpy(&value, at, sizeof(T));
  return value;
}

struct LasHeader {
  int version_minor = 0;
  std::uint32_t point_offset = 0;
  int format = 0;
  std::uint16_t record_length = 0;
  std::uint64_t points = 0;
  double scale[3] = {1, 1, 1}, offset[3] = {0, 0, 0};
};

struct LasLayout {
  std::uint16_t min_length;
  int rgb_at;  // byte offset of R G B (uint16 each), -1: none
};

LasLayout layout_of(int format) {
  switch (format) {
    case 0:
      return {20, -1};
    case 1:
      return {28, -1};
    case 2:
      return {26, 20};
    case 3:
      return {34, 28};
    case 6:
      return {30, -1};
    case 7:
      return {36, 30};
    default:  // 8
      return {38, 30};
  }
}

LasHeader read_header(std::ifstream& in, const std::string& path, std::uint64_t size) {
  unsigned char h[375] = {};
  in.read(reinterpret_cast<char*>(h), 227);
  if (in.gcount() != 227 || std::memcmp(h, "LASF", 4) != 0)
    throw Error(path, "header", "not a LAS file (no 'LASF' signature in a 227-byte header)");
  LasHeader header;
  const int major = h[24];
  header.version_minor = h[25];
  if (major != 1 || header.version_minor > 4)
    throw Error(path, "header",
                "LAS version " + std::to_string(major) + "." +
                    std::to_string(header.version_minor) + ": expected 1.0-1.4");
  const auto header_size = field<std::uint16_t>(h + 94);
  header.point_offset = field<std::uint32_t>(h + 96);
  const int raw_format = h[104];
  header.record_length = field<std::uint16_t>(h + 105);
  if (raw_format & 0xC0)
    throw Error(path, "point data format",
                "LAZ (compressed LAS) is not read; decompress it first (e.g. laszip -i " + path +
                    " -o out.las, or pdal translate)");
  header.format = raw_format;
  if (!(header.format <= 3 || (header.format >= 6 && header.format <= 8)))
    throw Error(path, "point data format",
                "format " + std::to_string(header.format) + ": expected 0-3 or 6-8");
  header.points = field<std::uint32_t>(h + 107);
  for (int k = 0; k < 3; ++k) {
    header.scale[k] = field<double>(h + 131 + 8 * k);
    header.offset[k] = field<double>(h + 155 + 8 * k);
    if (!(std::isfinite(header.scale[k]) && header.scale[k] != 0.0 &&
          std::isfinite(header.offset[k])))
      throw Error(path, std::string("header ") + "xyz"[k] + " scale/offset",
                  "expected a finite non-zero scale and a finite offset");
  }
  if (header.version_minor >= 4 && header_size >= 375) {
    in.read(reinterpret_cast<char*>(h + 227), 375 - 227);
    if (in.gcount() != 375 - 227) throw Error(path, "header", "the 1.4 header is truncated");
    const auto points64 = field<std::uint64_t>(h + 247);
    if (points64 > 0) header.points = points64;
  }
  const LasLayout layout = layout_of(header.format);
  if (header.record_length < layout.min_length)
    throw Error(path, "point data record length",
                std::to_string(header.record_length) + " bytes is shorter than format " +
                    std::to_string(header.format) + "'s " + std::to_string(layout.min_length));
  if (header.point_offset < header_size || header.point_offset > size ||
      header.points > (size - header.point_offset) / header.record_length)
    throw Error(path, "header",
                "the header claims " + std::to_string(header.points) + " points of " +
                    std::to_string(header.record_length) + " bytes from byte " +
                    std::to_string(header.point_offset) + ", more than the file's " +
                    std::to_string(size) + " bytes hold");
  return header;
}

// Calls visit(first, count, records) for consecutive runs of point records (about 4 MiB each,
// never more than the file holds: a record may be up to 64 KiB long), from the stream's position.
template <typename Visit>
void for_each_record_run(std::ifstream& in, const std::string& path, const LasHeader& header,
                         Visit&& visit) {
  in.clear();
  in.seekg(header.point_offset);
  constexpr std::uint64_t kRunBytes = std::uint64_t{4} << 20;
  const std::uint64_t per_run = std::max<std::uint64_t>(
      1, std::min<std::uint64_t>(header.points, kRunBytes / header.record_length));
  std::vector<unsigned char> buffer(per_run * header.record_length);
  for (std::uint64_t first = 0; first < header.points; first += per_run) {
    const std::uint64_t count = std::min(per_run, header.points - first);
    in.read(reinterpret_cast<char*>(buffer.data()),
            static_cast<std::streamsize>(count * header.record_length));
    if (static_cast<std::uint64_t>(in.gcount()) != count * header.record_length)
      throw Error(path, "point " + std::to_string(first), "the point data is truncated");
    visit(first, count, buffer.data());
  }
}

// Whether the file's colours use 16 bits (some channel above 255), which decides their scaling
// to 8 bits for every point: a pass over the colour fields alone.
bool colors_are_16_bit(std::ifstream& in, const std::string& path, const LasHeader& header,
                       const LasLayout& layout) {
  bool sixteen = false;
  for_each_record_run(in, path, header,
                      [&](std::uint64_t, std::uint64_t count, const unsigned char* records) {
                        for (std::uint64_t i = 0; i < count && !sixteen; ++i)
                          for (int c = 0; c < 3; ++c)
                            sixteen |= field<std::uint16_t>(records + i * header.record_length +
                                                            layout.rgb_at + 2 * c) > 255;
                      });
  return sixteen;
}

// Streams the points of `path` to sink(batch), `batch_points` at a time at most (0: one
// batch), every batch in the local frame of the first point (PointCloud::origin).
void read_las_points(const std::string& path, std::size_t batch_points,
                     const std::function<void(PointCloud&)>& sink) {
  std::ifstream in = open_input(path);
  const std::uint64_t size = file_size(path);
  const LasHeader header = read_header(in, path, size);
  const LasLayout layout = layout_of(header.format);
  const int shift = layout.rgb_at >= 0 && colors_are_16_bit(in, path, header, layout) ? 8 : 0;
  const std::uint64_t per_batch = batch_points > 0 ? batch_points : header.points;
  PointCloud cloud;
  const auto reserve = [&](std::uint64_t n) {
    cloud.positions.reserve(n);
    cloud.intensities.reserve(n);
    if (layout.rgb_at >= 0) cloud.colors.reserve(n);
  };
  reserve(std::min<std::uint64_t>(per_batch, header.points));
  for_each_record_run(
      in, path, header,
      [&](std::uint64_t first, std::uint64_t count, const unsigned char* records) {
        for (std::uint64_t i = 0; i < count; ++i) {
          const unsigned char* record = records + i * header.record_length;
          Eigen::Vector3d p;
          for (int k = 0; k < 3; ++k)
            p[k] = field<std::int32_t>(record + 4 * k) * header.scale[k] + header.offset[k];
          if (first + i == 0) {
            cloud.origin = local_origin_near(p);
            cloud.z_up = true;  // LAS z: heights (airborne and terrestrial surveys alike)
          }
          const Eigen::Vector3d local = p - cloud.origin;
          if (!local.allFinite() || (local.array().abs() > kMaxAbsCoordinate).any()) {
            char where[128];
            std::snprintf(where, sizeof where,
                          "(%.3f, %.3f, %.3f) lies more than 1e6 m from the "
                          "first point",
                          p.x(), p.y(), p.z());
            throw Error(
                path, "point " + std::to_string(first + i),
                std::string(where) + ": corrupt data or a cloud too large for one local frame");
          }
          cloud.positions.push_back(local.cast<float>());
          cloud.intensities.push_back(field<std::uint16_t>(record + 12));
          if (layout.rgb_at >= 0) {
            const auto channel = [&](int c) {
              return static_cast<std::uint8_t>(
                  field<std::uint16_t>(record + layout.rgb_at + 2 * c) >> shift);
            };
            cloud.colors.push_back(Rgb8{channel(0), channel(1), channel(2)});
          }
          if (cloud.size() == per_batch) {
            sink(cloud);
            cloud.positions.clear();
            cloud.intensities.clear();
            cloud.colors.clear();
          }
        }
      });
  if (!cloud.empty() || header.points == 0) sink(cloud);
}

}  // namespace

PointCloud read_las(const std::string& path) {
  PointCloud whole;
  read_las_points(path, 0, [&](PointCloud& cloud) { whole = std::move(cloud); });
  return whole;
}

void read_las_batches(const std::string& path, std::size_t batch,
                      const std::function<void(const PointCloud&)>& sink) {
  read_las_points(path, std::max<std::size_t>(batch, 1), [&](PointCloud& cloud) { sink(cloud); });
}

}  // namespace meshflow::io
