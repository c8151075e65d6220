#pragma once
// One entry point for every point-cloud format meshflow reads.

#include <string>

#include "runtime/point_cloud.h"

namespace meshflow::io {

/// Reads PLY (.ply), PCD (.pcd), text (.xyz, .txt, .pts, .asc) or 3DTK (.3d, with its .pose)
/// by extension. Throws meshflow::Error for unknown extensions and malformed files.
PointCloud read_point_cloud(const std::string& path);

}  // namespace meshflow::io
