#pragma once
// One entry point for every point-cloud format meshflow reads.

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

}  // namespace meshflow::io
