#pragma once
// An organized point cloud as the depth image it was made from. Kinect / OpenNI organized
// clouds (PCL's PCD frames) are pinhole back-projections: pixel (u, v) holds
// (x, y, z) = ((u - cx) z / fx, (v - cy) z / fy, z). Recovering the depth image and the
// intrinsics lets such a cloud take the depth-image path (image-neighbour normals, projective
// distance, TSDF fusion, per-frame triangulation) instead of nearest-neighbour searches.

#include <optional>

#include "runtime/depth_frame.h"
#include "runtime/point_cloud.h"

namespace meshflow {

/// The depth frame behind `cloud`, when it is organized (width x height points) and its valid
/// points (finite, z > 0 after subtracting the sensor origin) are a pinhole projection seen from
/// the sensor origin looking along +z: fx, cx and fy, cy are fitted by least squares to
/// u = fx x/z + cx and v = fy y/z + cy, and every valid point must reproject within
/// `max_residual_px` of its pixel. The frame: F32 depth z in metres (0 = invalid), the fitted
/// intrinsics, colour (RGB) when the cloud has colours, pose = translation to the sensor origin.
/// nullopt when the cloud is not organized, has fewer than 16 valid points, has a valid point
/// behind the sensor or does not fit (e.g. a cloud already moved into a world frame). Serial,
/// deterministic; O(points).
std::optional<DepthFrame> depth_frame_from_organized(const PointCloud& cloud,
                                                     double max_residual_px = 0.05);

}  // namespace meshflow
