#pragma once
// One entry point for every point-cloud format meshflow reads.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

#include "runtime/point_cloud.h"

namespace meshflow::io {

/// Reads PLY (.ply), PCD (.pcd), text (.xyz, .txt, .pts, .asc, .csv), 3DTK (.3d, with its
/// .pose) or LAS (.las) by extension. Throws meshflow::Error for unknown extensions (LAZ: a
/// message saying to decompress it) and malformed files.
PointCloud read_point_cloud(const std::string& path);

/// The same with the columns of a text cloud given (see read_xyz); `columns` must be empty
/// for the other formats (a meshflow::Error naming --columns otherwise).
PointCloud read_point_cloud(const std::string& path, const std::string& columns);

/// The points of `path` (columns as above) handed to `sink` in file order, at most `batch` at a
/// time, each piece with the file's origin and sensor. PLY and LAS are streamed (memory: one
/// batch);
/// the other formats are read whole and then handed over in pieces. The cloud passed to `sink`
/// is reused after it returns. Throws as read_point_cloud() does.
void for_each_point_batch(const std::string& path, const std::string& columns, std::size_t batch,
                          const std::function<void(const PointCloud&)>& sink);

/// Whether the points of `path` can be read by byte range (for_each_point_batch_in_range), so
/// threads or MPI ranks each read their own part of the file and none reads it whole.
struct PointRanges {
  std::uint64_t points = 0;  ///< points the file declares (when by_byte_range)
  bool by_byte_range = false;
  /// Why not: ASCII PLY and the text formats (.xyz .txt ...: a line's byte is known only by
  /// reading the lines before it), PCD and 3DTK (read whole), PLY with list properties in or
  /// before its vertex rows, LAS (its colours' scale is decided over the whole file).
  std::string why_not;
};

/// PointRanges of `path` (columns as read_point_cloud). O(header).
PointRanges point_ranges(const std::string& path, const std::string& columns);

/// Points [first, first + count) of a file that point_ranges() says can be read by byte range,
/// handed to `sink` at most `batch` at a time in file order, in the local frame
/// for_each_point_batch() gives (the file's first point's). Thread-safe (each call its own
/// stream). Throws meshflow::Error as read_ply_vertex_range() does.
void for_each_point_batch_in_range(const std::string& path, const std::string& columns,
                                   std::uint64_t first, std::uint64_t count, std::size_t batch,
                                   const std::function<void(const PointCloud&)>& sink);

}  // namespace meshflow::io
