#pragma once
// Feature vertices of a planar mesh onto the lines and corners where their regions' planes meet
// (the planes step): projecting only the vertices inside one region leaves the vertices of a
// sharp edge where the extraction put them, off both planes by up to a fraction of a voxel,
// and pulling them onto one of the planes (as a plain plane fit would) moves the edge.

#include <cstddef>

#include "nodes/optimize/features.h"
#include "runtime/half_edge_mesh.h"
#include "runtime/planar_segmentation.h"

namespace meshflow {

struct PlaneIntersectionReport {
  std::size_t to_line = 0;    ///< feature vertices moved onto the line of two planes
  std::size_t to_corner = 0;  ///< onto the common point of three or more
  std::size_t refused = 0;    ///< too far, or a face would turn over
};

/// Moves every feature vertex of `mesh` (`features`: detect_features() of it; line and corner
/// vertices) whose faces all lie in regions of `segmentation` (grow_planar_regions() of it),
/// two or more regions whose planes meet (normals more than 20 degrees apart), onto those
/// planes: the smallest move onto their least-squares point, i.e. two planes: onto their line
/// (the vertex keeps its place along it), three: onto their corner. A move farther than
/// `max_move` metres (0: any) or one that would leave a face without area or turn it by more
/// than 90 degrees is refused. Targets are computed in parallel from the positions given,
/// applied serially in vertex order; deterministic. O(V + F).
PlaneIntersectionReport project_onto_plane_intersections(HalfEdgeMesh& mesh,
                                                         const PlanarSegmentation& segmentation,
                                                         const MeshFeatures& features,
                                                         float max_move = 0.0f);

}  // namespace meshflow
