#pragma once
// DepthFrame: one depth image with its camera model and pose.

#include <Eigen/Geometry>
#include <cstdint>

#include "runtime/image.h"

namespace meshflow {

/// Pinhole camera: pixel (u, v) of a point (x, y, z) in the camera frame (x right, y down,
/// z forward, metres) is u = fx x / z + cx, v = fy y / z + cy.
struct PinholeIntrinsics {
  int width = 640, height = 480;
  float fx = 525.0f, fy = 525.0f, cx = 319.5f, cy = 239.5f;
};

/// A depth image: U16 in units of 1/depth_scale metres (0 = no measurement), or F32 in metres
/// (0 or NaN = no measurement); optional colour (RGB8, same size).
struct DepthFrame {
  Image depth;
  float depth_scale = 1000.0f;  ///< raw units per metre for U16 (1000 = mm, 5000 = TUM)
  Image color;
  PinholeIntrinsics intrinsics;
  Eigen::Isometry3f T_world_camera = Eigen::Isometry3f::Identity();
  double timestamp_s = 0.0;
};

/// Throws meshflow::Error naming the field unless `frame` can be used: a non-empty U16 or F32
/// depth image of the intrinsics' size, a positive finite depth_scale (U16), positive
/// finite focal lengths, a finite principal point and a finite pose. O(1).
void check_depth_frame(const DepthFrame& frame);

/// Depth of `frame` in metres as a new F32 image; invalid pixels (0, negative, NaN, infinite)
/// are 0. Checks the frame first (check_depth_frame()). O(pixels).
Image depth_in_metres(const DepthFrame& frame);
/// The same into `out`, whose pixels are reused when it already is an F32 image of the frame's
/// size (so a caller converting frame after frame allocates once); `out` must not share its
/// pixels with an image the caller still reads. Parallel over rows; O(pixels).
void depth_in_metres(const DepthFrame& frame, Image& out);

}  // namespace meshflow
