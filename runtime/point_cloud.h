#pragma once
// PointCloud: structure of arrays in metres, world frame unless stated otherwise.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "runtime/rgb8.h"

namespace meshflow {

/// A point cloud as parallel arrays. `positions` is always present; `normals`, `colors` and
/// `intensities` are either empty or exactly as long as `positions`.
/// An organized cloud (from a depth camera or a range grid) has width * height == size()
/// and height > 1; invalid pixels are NaN. Filters that drop points make it unorganized.
struct PointCloud {
  std::vector<Eigen::Vector3f> positions;  ///< metres
  std::vector<Eigen::Vector3f> normals;    ///< unit length, oriented towards the sensor
  std::vector<Rgb8> colors;                ///< 8-bit RGB
  std::vector<float> intensities;          ///< sensor units, unscaled
  std::uint32_t width = 0;                 ///< organized grid width (0 if unorganized)
  std::uint32_t height = 0;                ///< organized grid height (0 if unorganized)
  Eigen::Vector3f sensor_origin = Eigen::Vector3f::Zero();  ///< where the sensor stood
  /// Georeferenced inputs (e.g. LAS in UTM, millions of metres, which floats hold only to
  /// decimetres): the world coordinates of the local frame `positions` (and sensor_origin, and
  /// every mesh made of them) are relative to. Zero for everything else.
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  bool has_sensor_origin = false;
  /// The format fixes +z as up (LAS: heights above a datum), so normals of a scene without a
  /// sensor position are turned up rather than outward (NormalOrientation::kAuto).
  bool z_up = false;

  /// Number of points.
  std::size_t size() const { return positions.size(); }
  /// Whether the cloud has no points.
  bool empty() const { return positions.empty(); }
  /// Whether every point has a normal.
  bool has_normals() const { return !normals.empty(); }
  /// Whether every point has a colour.
  bool has_colors() const { return !colors.empty(); }
  /// Whether every point has an intensity.
  bool has_intensities() const { return !intensities.empty(); }
  /// Whether the points form a width x height grid (a depth camera's or a scanner's rows).
  bool is_organized() const {
    return height > 1 && static_cast<std::size_t>(width) * height == positions.size();
  }
};

/// Copies what `from` says of its frame and sensor (origin, sensor_origin, has_sensor_origin,
/// z_up) to `to`, points untouched. O(1).
void copy_frame_description(const PointCloud& from, PointCloud& to);

/// Returns the points at `indices` (in that order) with all their attributes; the result is
/// unorganized and keeps the sensor origin. O(indices.size()), parallel, deterministic.
PointCloud select_points(const PointCloud& cloud, const std::vector<std::uint32_t>& indices);

/// Number of points whose three coordinates are finite. O(n).
std::size_t count_finite_points(const PointCloud& cloud);

/// Axis-aligned bounds of the finite points (an empty box if there are none). O(n).
Eigen::AlignedBox3f finite_bounds(const PointCloud& cloud);

}  // namespace meshflow
