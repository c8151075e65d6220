#pragma once
// One entry point for every point-cloud format meshflow reads.

#include <cstddef>
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

}  // namespace meshflow::io
