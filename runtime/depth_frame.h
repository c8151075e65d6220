#pragma once
// DepthFrame: one depth image with its camera model and pose.

#include <Eigen/Geometry>
#include <cstdint>
#include <opencv2/core.hpp>

namespace meshflow {

/// Pinhole camera: pixel (u, v) of a point (x, y, z) in the camera frame (x right, y down,
/// z forward, metres) is u = fx x / z + cx, v = fy y / z + cy.
struct PinholeIntrinsics {
  int width = 640, height = 480;
  float fx = 525.0f, fy = 525.0f, cx = 319.5f, cy = 239.5f;
};

/// A depth image: CV_16U in units of 1/depth_scale metres (0 = no measurement), or CV_32F in
/// metres (0 or NaN = no measurement); optional colour (CV_8UC3, RGB order, same size).
struct DepthFrame {
  cv::Mat depth;
  float depth_scale = 1000.0f;  ///< raw units per metre for CV_16U (1000 = mm, 5000 = TUM)
  cv::Mat color;
  PinholeIntrinsics intrinsics;
  Eigen::Isometry3f T_world_camera = Eigen::Isometry3f::Identity();
  double timestamp_s = 0.0;
};

/// Throws meshflow::Error naming the field unless `frame` can be used: a non-empty CV_16U or
/// CV_32F depth image of the intrinsics' size, a positive finite depth_scale (CV_16U), positive
/// finite focal lengths, a finite principal point and a finite pose. O(1).
void check_depth_frame(const DepthFrame& frame);

/// Depth of `frame` in metres as CV_32F; invalid pixels (0, negative, NaN, infinite) are 0.
/// Checks the frame first (check_depth_frame()). O(pixels).
cv::Mat depth_in_metres(const DepthFrame& frame);

/// Makes OpenCV run its functions on the calling thread (cv::setNumThreads(0)), once per
/// process. meshflow parallelizes across frames and pixels with oneTBB under one thread limit;
/// OpenCV's own parallel backend would oversubscribe the cores and escape that limit.
/// Called by every meshflow function that uses OpenCV. Thread-safe.
void run_opencv_on_calling_thread();

}  // namespace meshflow
