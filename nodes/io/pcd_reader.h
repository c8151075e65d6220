#pragma once
// PCD (Point Cloud Library) reader: DATA ascii, binary and binary_compressed (LZF).

#include <string>

#include "runtime/point_cloud.h"

namespace meshflow::io {

/// Reads a PCD v0.5-0.7 file. Recognised fields: x y z (required), normal_x normal_y normal_z,
/// rgb / rgba (packed 0x00RRGGBB in a float or uint32), intensity; every other field (any
/// COUNT) is skipped. Organized clouds (HEIGHT > 1) keep width/height and their NaN points.
/// VIEWPOINT is ignored: the points are taken as stored (sensor frame for PCL grabbers).
/// Throws meshflow::Error naming the file and the header line, point or field on malformed,
/// truncated or inconsistent input. Memory: the output plus one chunk (or the decompressed
/// block for binary_compressed). O(file size).
PointCloud read_pcd(const std::string& path);

}  // namespace meshflow::io
