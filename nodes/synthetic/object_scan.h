#pragma once
// A closed test object (closed_objects.h) scanned the way a turntable or handheld scanner scans
// it: a few depth views from a ring around it, back-projected and merged into one cloud of
// points without normals or sensor, plus stray points scattered uniformly in its bounding box.
// Parts of the surface (the underside, concavities) stay unseen: the input of outlier-removal
// and hole-closing tests, with exact ground truth.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "nodes/synthetic/closed_objects.h"
#include "runtime/depth_frame.h"
#include "runtime/point_cloud.h"

namespace meshflow::synthetic {

struct ObjectScanConfig {
  int views = 8;                  ///< camera positions on one ring around the object
  float elevation_deg = 25.0f;    ///< the ring's height above the object's centre, degrees
  int width = 200, height = 150;  ///< image size (scaled_default_camera)
  float noise_sigma = 0.001f;     ///< Gaussian range noise, metres
  /// Uniform points in the bounding box (grown by 10 % of each side), as a fraction of the
  /// surface points: 0.005 = 0.5 %.
  float outlier_fraction = 0.0f;
  std::uint32_t seed = 1;
};

struct ObjectScan {
  /// The merged points: surface points first, then the outliers; no normals, no sensor.
  PointCloud cloud;
  std::size_t outliers = 0;                  ///< the last `outliers` points of cloud
  std::vector<Eigen::Vector3f> sensors;      ///< each view's camera centre, metres
  std::vector<Eigen::Isometry3f> poses;      ///< each view's T_world_camera
  PinholeIntrinsics intrinsics;              ///< of every view
  std::vector<std::uint32_t> first_of_view;  ///< index of each view's first point (views + 1)
};

/// Renders `config.views` depth images of `object` (render_object_depth) from a ring at
/// `elevation_deg`, looking at its centre from where it fills about 70 % of the image, and
/// merges their valid pixels' points in world coordinates (metres). Deterministic for a seed.
/// Parallel over image rows; O(views x pixels x steps x patches).
ObjectScan scan_object(const ClosedObject& object, const ObjectScanConfig& config = {});

}  // namespace meshflow::synthetic
