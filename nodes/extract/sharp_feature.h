#pragma once
// Sharp-feature detection and placement for Extended Marching Cubes (Kobbelt et al. 2001,
// section 3): a cell's surface patch has a sharp feature when the normals at its edge
// crossings open up beyond an angle; the feature vertex is where their tangent planes meet.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>

namespace meshflow {

struct SharpFeatureConfig {
  /// A patch whose normals include two more than this many degrees apart has a feature.
  float edge_angle_deg = 30.0f;
  /// A feature is a corner (three planes) when some normal leaves the plane spanned by the two
  /// most different normals by more than this many degrees; otherwise an edge (two planes).
  float corner_angle_deg = 30.0f;
  /// A feature point farther outside its cell than this fraction of the cell size is rejected
  /// (the tangent planes meet elsewhere: the patch only grazes a feature); nearer ones are
  /// clamped into the cell.
  float max_outside = 0.25f;
};

enum class FeatureKind { kNone, kEdge, kCorner };

struct FeaturePoint {
  FeatureKind kind = FeatureKind::kNone;
  Eigen::Vector3f position = Eigen::Vector3f::Zero();  ///< valid when kind != kNone
};

/// Classifies the patch through `count` surface points with unit normals and, for an edge or a
/// corner, solves the quadric error function sum_i (n_i . (x - p_i))^2 by a truncated
/// eigen-decomposition around the points' centroid (rank 2 for an edge: the point of the
/// feature line nearest the centroid; rank 3 for a corner), then clamps it into `cell`.
/// Pure function, thread-safe; O(count^2).
FeaturePoint sharp_feature(const Eigen::Vector3f* points, const Eigen::Vector3f* normals,
                           std::size_t count, const Eigen::AlignedBox3f& cell,
                           const SharpFeatureConfig& config = {});

}  // namespace meshflow
