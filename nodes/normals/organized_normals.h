#pragma once
// Back-projection of a filtered depth image to an organized cloud, with normals from image
// neighbours (no nearest-neighbour search needed).

#include "runtime/image.h"

#include "runtime/depth_frame.h"
#include "runtime/point_cloud.h"

namespace meshflow {

/// Organized cloud (width x height) in the world frame: pixel (u, v) with depth d > 0 maps to
/// T_world_camera * ((u - cx) d / fx, (v - cy) d / fy, d); invalid pixels are NaN. Normals are
/// the cross product of central differences to the 4-neighbours (one-sided at gaps), oriented
/// towards the camera; pixels without a neighbour in both directions get NaN (dropped later).
/// Colours are copied when the frame has them. Parallel over rows, deterministic; O(pixels).
PointCloud back_project(const DepthFrame& frame, const Image& depth_m);

/// The points of back_project() that have a position and a normal, in row-major pixel order,
/// as an unorganized cloud (what the reconstruction needs; skips storing the invalid pixels).
/// Same values as back_project(); parallel over rows, deterministic; O(pixels).
PointCloud back_project_valid(const DepthFrame& frame, const Image& depth_m);

}  // namespace meshflow
