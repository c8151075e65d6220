#pragma once
// 3DTK scan reader: scanNNN.3d (ASCII x y z in cm, left-handed, y up) with scanNNN.pose.

#include <Eigen/Geometry>
#include <optional>
#include <string>

#include "runtime/point_cloud.h"

namespace meshflow::io {

/// Options of the 3DTK reader. Defaults are 3DTK's slam6D configuration for the Kurt3D data.
struct Scan3dOptions {
  double min_range_cm = 48.0;    ///< closer returns are invalid (sensor housing, dust)
  double max_range_cm = 3275.0;  ///< returns at or beyond this are "no echo" (3276 cm)
};

/// Reads a 3DTK pose file: "tx ty tz" in cm, then "rx ry rz" in degrees. Returns the
/// scan-to-world transform in meshflow's right-handed metric frame (x forward, y left, z up).
/// Throws meshflow::Error naming the file and line on malformed input, a non-finite value or a
/// translation beyond +-1e6 m.
Eigen::Isometry3f read_3dtk_pose(const std::string& path);

/// Reads a 3DTK .3d scan and maps it to metres in the world frame. The pose is read from
/// `pose_path`, or from the .pose file beside the scan when `pose_path` is empty; when that
/// file does not exist the scan frame is used as the world frame. Points outside the valid
/// range (Scan3dOptions) are dropped. The sensor origin is the pose's translation.
/// A first line that is not three numbers (the old "W x H" header) is skipped.
/// Throws meshflow::Error naming the file and line on malformed input. O(file size).
PointCloud read_3dtk_scan(const std::string& path, const Scan3dOptions& options = {},
                          const std::string& pose_path = "");

}  // namespace meshflow::io
