#pragma once
// Point-cloud filters: non-finite removal, crop box / range, voxel-grid downsampling and
// statistical outlier removal. Each is a pure function; filter_cloud() composes them.
// All are parallel and deterministic (same output for any thread count).

#include <Eigen/Geometry>
#include <cstdint>
#include <limits>

#include "runtime/point_cloud.h"

namespace meshflow {

/// What filter_cloud() removed, stage by stage.
struct FilterCounts {
  std::size_t input = 0;
  std::size_t non_finite = 0;  ///< NaN or Inf coordinates
  std::size_t cropped = 0;     ///< outside the crop box or the range limits
  std::size_t merged = 0;      ///< folded into voxel-grid centroids
  std::size_t outliers = 0;    ///< statistical outliers
  /// Removed by the pipeline's index stage (outlier_cluster): points with no neighbour within
  /// the link radius, and points of clusters smaller than outlier_cluster.
  std::size_t isolated = 0;
  std::size_t sparse_clusters = 0;
  std::size_t output = 0;
};

struct FilterConfig {
  /// Keep only points inside [crop_min, crop_max] (metres, world); the default keeps all.
  Eigen::Vector3f crop_min = Eigen::Vector3f::Constant(-std::numeric_limits<float>::infinity());
  Eigen::Vector3f crop_max = Eigen::Vector3f::Constant(std::numeric_limits<float>::infinity());
  float min_range = 0.0f;       ///< metres from the sensor origin (needs has_sensor_origin)
  float max_range = 0.0f;       ///< metres from the sensor origin; 0 = unlimited
  float voxel_size = 0.0f;      ///< voxel-grid downsampling cell in metres; 0 = off
  int outlier_k = 0;            ///< neighbours for outlier removal; 0 = off (PCL's default is 50)
  float outlier_stddev = 1.0f;  ///< remove points whose mean neighbour distance exceeds
                                ///< mean + outlier_stddev * stddev over the cloud
  /// Outliers that cannot make surfaces (nodes/filter/point_clusters.h): points in clusters of
  /// fewer than this many points, a cluster being the points linked by neighbour links of at
  /// most outlier_radius_voxels voxels. Removed by the pipeline's index stage with the kd-tree
  /// it builds for normals (not by filter_cloud()); unorganized clouds only. 0 = off.
  std::size_t outlier_cluster = 20;
  /// Link length of outlier_cluster in voxels (of the voxel size in use, or of the one the
  /// points' spacing suggests where that is larger): a point farther than this from every
  /// other gives no valid distance sample shared with them (DistanceConfig's
  /// max_distance_voxels is 2), so it cannot join their surface. A cloud with no cluster of
  /// outlier_cluster points is left whole.
  float outlier_radius_voxels = 2.0f;

  /// True when filter_cloud() with this config removes nothing but non-finite points.
  bool keeps_every_finite_point() const {
    constexpr float kInf = std::numeric_limits<float>::infinity();
    return (crop_min.array() == -kInf).all() && (crop_max.array() == kInf).all() &&
           min_range <= 0.0f && max_range <= 0.0f && voxel_size <= 0.0f && outlier_k <= 0;
  }
};

/// Indices of points whose three coordinates are finite. O(n).
std::vector<std::uint32_t> finite_point_indices(const PointCloud& cloud);

/// Indices of points inside [crop_min, crop_max] and within [min_range, max_range] of the sensor
/// origin (range limits ignored when the cloud has no sensor origin). O(n).
std::vector<std::uint32_t> crop_indices(const PointCloud& cloud, const FilterConfig& config);

/// One point per occupied cell of edge `voxel_size`: the centroid of the cell's points (and the
/// mean of their normals, colours, intensities). Output ordered by cell key. O(n log n).
PointCloud voxel_grid_downsample(const PointCloud& cloud, float voxel_size);

/// Indices of points that are not statistical outliers: a point is an outlier if the mean
/// distance to its k nearest neighbours exceeds mean + stddev_mul * stddev of that statistic
/// over the cloud (PCL's StatisticalOutlierRemoval). O(n k log n).
std::vector<std::uint32_t> statistical_inlier_indices(const PointCloud& cloud, int k,
                                                      float stddev_mul);

/// Applies, in order: non-finite removal, crop/range, voxel grid, outlier removal.
/// `counts` (optional) receives what each step removed.
/// Standard deviations (metres) of the finite points along their three principal axes,
/// ascending: (0, 0, s) for points on a line, (0, s1, s2) on a plane. Parallel reduction in
/// fixed blocks, deterministic; O(n).
Eigen::Vector3d principal_extents(const PointCloud& cloud);

PointCloud filter_cloud(const PointCloud& cloud, const FilterConfig& config,
                        FilterCounts* counts = nullptr);

}  // namespace meshflow
