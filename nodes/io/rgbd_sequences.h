#pragma once
// RGB-D sequence readers: the Redwood / Open3D layout and the TUM RGB-D layout.

#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "nodes/io/sequence.h"
#include "runtime/depth_frame.h"

namespace meshflow::io {

/// Reads a 16-bit single-channel depth image (PNG, TIFF) into frame.depth (U16).
/// Throws meshflow::Error naming the file when it is missing, corrupt or of another type.
Image read_depth_image(const std::string& path);

/// Reads a Redwood .log trajectory: blocks of one "i j k" line and four rows of a row-major
/// camera-to-world 4x4 matrix. Returns one pose per block, in block order. Throws
/// meshflow::Error naming the file and line on malformed input, a matrix that is not rigid or a
/// translation beyond +-1e6 m.
std::vector<Eigen::Isometry3f> read_trajectory_log(const std::string& path);

/// One pose of a timed trajectory: seconds, and the camera-to-world transform.
struct TimedPose {
  double t;
  Eigen::Isometry3f T_world_camera;
};

/// Reads a TUM RGB-D trajectory (groundtruth.txt: "timestamp tx ty tz qx qy qz qw" lines, world
/// from camera, '#' comments), sorted by timestamp. Throws meshflow::Error naming the file and
/// line for a malformed line, a non-finite value, a quaternion that is not unit length (within
/// 1 %) or a translation beyond +-1e6 m. O(lines log lines).
std::vector<TimedPose> read_tum_groundtruth(const std::string& path);

/// Reads Open3D's camera JSON ({"width", "height", "intrinsic_matrix": 9 numbers, column-major}).
/// Throws meshflow::Error naming the file and the field for invalid JSON, a missing field, a
/// value that is not a number or out of range (width and height whole numbers in 1..65535,
/// fx and fy in [0.001, 1e6], cx and cy within +-1e6 pixels).
PinholeIntrinsics read_intrinsics_json(const std::string& path);

/// A Redwood / Open3D RGB-D directory: depth/*.png (16-bit, mm), optional color/*.jpg|png paired
/// by sorted order, trajectory.log (or odometry.log) with one camera-to-world pose per frame, and
/// a camera JSON (the first *.json in the directory; PrimeSense defaults if none). A frame
/// without a pose fails to load with a message naming the trajectory file.
std::unique_ptr<Sequence> open_redwood_directory(const std::string& directory);

/// A TUM RGB-D directory: depth.txt ("timestamp filename" lines, '#' comments), depth PNGs with
/// depth scale 5000, groundtruth.txt ("timestamp tx ty tz qx qy qz qw", world from camera),
/// associated by nearest timestamp within 20 ms, optional rgb.txt, intrinsics from a camera
/// JSON in the directory or the ROS defaults (525, 525, 319.5, 239.5). A frame without a pose
/// within 20 ms fails to load, naming depth.txt and its timestamp. Non-finite timestamps or pose
/// values and translations beyond +-1e6 m are errors naming the file and line.
std::unique_ptr<Sequence> open_tum_directory(const std::string& directory);

/// A directory of depth images without poses (e.g. a PCL grabber's *_depth.tiff or
/// *_depth.pclzf): every image whose name contains "depth" (.png, .tif, .tiff, .pclzf; 16-bit,
/// millimetres), in name order, paired with the *rgb* / *color* images when their counts agree.
/// Intrinsics from a camera JSON in the directory, else from a PCL grabber XML (<depth> focal
/// lengths, principal point, z_multiplication_factor), else Kinect defaults (525, 525, 320, 240).
/// Frames are in the camera frame (identity pose): meshed per frame, not fused.
std::unique_ptr<Sequence> open_depth_image_directory(const std::string& directory);

}  // namespace meshflow::io
