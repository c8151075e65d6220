#include "nodes/io/read_point_cloud.h"

#include <algorithm>

#include "nodes/io/las_reader.h"
#include "nodes/io/parse_util.h"
#include "nodes/io/pcd_reader.h"
#include "nodes/io/ply_reader.h"
#include "nodes/io/scan3d_reader.h"
#include "nodes/io/xyz_reader.h"
#include "runtime/error.h"

namespace meshflow::io {

namespace {
bool is_text_cloud(const std::string& ext) {
  return ext == ".xyz" || ext == ".txt" || ext == ".pts" || ext == ".asc" || ext == ".csv";
}
}  // namespace

PointCloud read_point_cloud(const std::string& path, const std::string& columns) {
  if (columns.empty()) return read_point_cloud(path);
  if (!is_text_cloud(lower_extension(path)))
    throw Error("--columns", path, "only text clouds (.xyz .txt .pts .asc .csv) have columns");
  return read_xyz(path, columns);
}

PointCloud read_point_cloud(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext == ".ply") return read_ply(path);
  if (ext == ".pcd") return read_pcd(path);
  if (is_text_cloud(ext)) return read_xyz(path);
  if (ext == ".3d") return read_3dtk_scan(path);
  if (ext == ".las") return read_las(path);
  if (ext == ".laz")
    throw Error(path, "",
                "LAZ (compressed LAS) is not read; decompress it first (laszip -i " + path +
                    " -o out.las, or pdal translate)");
  throw Error(path, "",
              "unknown point cloud format '" + ext +
                  "' (expected .ply, .pcd, .xyz, .txt, .pts, .asc, .csv, .3d or .las)");
}

void for_each_point_batch(const std::string& path, const std::string& columns, std::size_t batch,
                          const std::function<void(const PointCloud&)>& sink) {
  batch = std::max<std::size_t>(batch, 1);
  if (columns.empty() && lower_extension(path) == ".ply")
    return read_ply_batches(path, batch, sink);
  PointCloud whole = read_point_cloud(path, columns);
  if (whole.size() <= batch) return sink(whole);
  PointCloud piece;
  copy_frame_description(whole, piece);
  for (std::size_t begin = 0; begin < whole.size(); begin += batch) {
    const std::size_t end = std::min(whole.size(), begin + batch);
    const auto slice = [&](const auto& from, auto& to) {
      if (from.empty()) return;
      to.assign(from.begin() + static_cast<std::ptrdiff_t>(begin),
                from.begin() + static_cast<std::ptrdiff_t>(end));
    };
    slice(whole.positions, piece.positions);
    slice(whole.normals, piece.normals);
    slice(whole.colors, piece.colors);
    slice(whole.intensities, piece.intensities);
    sink(piece);
  }
}

PointRanges point_ranges(const std::string& path, const std::string& columns) {
  PointRanges ranges;
  const std::string ext = lower_extension(path);
  if (!columns.empty() || ext != ".ply") {
    ranges.why_not =
        ext == ".las" ? "LAS: its colours' scale (8 or 16 bits) is decided over the whole file"
        : is_text_cloud(ext)
            ? "a text cloud: a line's byte is known only by reading the lines before it"
            : "the " + ext + " reader reads the file whole";
    return ranges;
  }
  const PlyVertexRows rows = ply_vertex_rows(path);
  ranges.points = rows.count;
  ranges.by_byte_range = rows.by_byte_range;
  ranges.why_not = rows.why_not;
  return ranges;
}

void for_each_point_batch_in_range(const std::string& path, const std::string& columns,
                                   std::uint64_t first, std::uint64_t count, std::size_t batch,
                                   const std::function<void(const PointCloud&)>& sink) {
  const PointRanges ranges = point_ranges(path, columns);
  if (!ranges.by_byte_range) throw Error(path, "byte ranges", ranges.why_not);
  read_ply_vertex_range(path, first, count, batch, sink);
}

}  // namespace meshflow::io
