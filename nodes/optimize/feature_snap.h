#pragma once
// Feature vertices put back on their edge: a vertex of a sharp edge is moved to the point
// nearest to the planes of the faces on each of its sides (two planes: their intersection line;
// three or more: their common point), as fitted to the free vertices there. Extraction leaves
// some feature vertices off the true edge (extended marching cubes on a box: up to 0.9 voxel
// outside it at a few cells near the edges); the reducing steps keep feature vertices where
// they are and give them larger faces, so their error spreads over more area.

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "nodes/optimize/features.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {

/// A plane normal . x = offset (unit normal, metres).
struct FeaturePlane {
  Eigen::Vector3d normal;
  double offset = 0.0;
};

/// Whether two of `planes` have normals more than 20 degrees apart (they meet in a line).
/// O(planes^2).
bool planes_meet(const std::vector<FeaturePlane>& planes);

/// The smallest move of `point` onto the least-squares point of `planes`: only across the
/// directions their normals span (two planes: onto their line, the point keeps its place along
/// it; three independent ones: onto their common point). Zero without planes. O(planes).
Eigen::Vector3d move_onto_planes(const Eigen::Vector3d& point,
                                 const std::vector<FeaturePlane>& planes);

struct FeatureSnapReport {
  std::size_t feature_vertices = 0;  ///< line and corner vertices looked at
  std::size_t moved = 0;             ///< of them, moved
  float largest_move = 0.0f;         ///< metres
};

/// Moves the feature vertices of `mesh` (`features` = detect_features() of it) onto the planes
/// of their sides. A side is the fan of faces between two sharp edges at the vertex; its plane
/// is fitted to the free vertices within two rings of it on that side (at least 5 of them, their
/// robust deviation from it, 1.4826 x the median distance, at most `flatness` metres: a curved
/// or noisy side gives no plane, nor does a side without free vertices next to it, e.g. a
/// corner's single triangle between two feature edges, so such a corner stays), by least
/// squares refitted through the vertices within 3 robust deviations of it (stray vertices next
/// to an edge do not tilt an exact side). With planes on at least two sides whose normals
/// differ by more than 20 degrees the vertex takes the smallest move onto the least-squares
/// point of the planes (along a line it stays where it was), when that is at most `max_move`
/// metres away, more than 3 times the largest robust deviation of its sides (the planes are
/// known better than the vertex lies on them: an exact edge between rough sides stays), and
/// turns none of its faces by
/// more than 90 degrees. Serial, deterministic; O(F x
/// valence^2).
FeatureSnapReport snap_feature_vertices(TriangleMesh& mesh, const MeshFeatures& features,
                                        float max_move, float flatness);

}  // namespace meshflow
