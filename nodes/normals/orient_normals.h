#pragma once
// Consistent orientation of normals without a sensor position: propagation over a minimum
// spanning tree of the neighbour graph (Hoppe et al. 1992), for object scans, CAD samples and
// any cloud whose points were not seen from one place.
//
// Neighbours are compared by Hoppe's n_a . n_b. Koenig and Gumhold's (2009) mirror rule (the
// normal at b predicted by mirroring n_a in the plane bisecting a-b) is more confident across
// sharp edges and thin walls on exact samples, but measured here it fails as soon as the
// points are noisy (0.2 voxel of noise: half of the normals wrong, against 0.2 % with the dot
// product): the segment between close neighbours then points along the normal by chance. Sharp
// edges need no special rule: the plane fits there blend the two faces, and the tree crosses
// the edge through them.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "nodes/search/neighbour_table.h"

namespace meshflow {

/// Which way each component of the neighbour graph faces once its normals agree with each
/// other (propagation fixes signs only relative to one another).
enum class ComponentSide {
  /// Closed objects: outward, i.e. the sum of n_i . (p_i - centroid) over the component's
  /// points positive; where that sum is indecisive (an open, flat piece), the normal of its
  /// point of largest x has a non-negative x; a component inside an odd number of larger ones
  /// (a cavity's wall, a hollow ball's inner shell) then faces inward, towards the cavity.
  kOutward,
  /// Open scenes seen from one place (a camera-frame cloud): the sum over the component's
  /// points of n_i . (point - p_i) / |point - p_i| positive.
  kTowardPoint,
  /// Terrain (heights along an axis, e.g. airborne LAS): the sum of n_i . axis positive.
  kAlongAxis,
  /// kTowardPoint when the cloud looks like one view from `point`: with every component facing
  /// it, sum |sum over a component of n_i . v_i| >= min_view_agreement x sum |n_i . v_i| (v_i
  /// the unit direction from p_i to the point; 1 for a single view, near 0 for a closed object
  /// seen from outside); kOutward otherwise.
  kViewOrOutward,
  /// kAlongAxis when the cloud looks like one surface facing along `axis` (a terrain tile):
  /// with every component facing along it, sum |sum over a component of n_i . axis| >=
  /// min_view_agreement x sum |n_i . axis| (1 for a height field, near 0 for a closed object
  /// such as a thin plate, whose top and bottom cancel); kOutward otherwise.
  kAxisOrOutward
};

struct PropagationConfig {
  /// Passes of a final vote in which a normal that disagrees with the confidence-weighted
  /// majority of its neighbours is turned over (0 = off). Repairs single points that the tree
  /// reached through a poor edge.
  int vote_passes = 2;
  ComponentSide side = ComponentSide::kOutward;
  Eigen::Vector3f point = Eigen::Vector3f::Zero();  ///< kTowardPoint / kViewOrOutward, metres
  Eigen::Vector3f axis = Eigen::Vector3f::UnitZ();  ///< kAlongAxis (any length but zero)
  /// kViewOrOutward's and kAxisOrOutward's threshold. Measured: single camera views 0.9-1.0, closed
  /// objects around the point 0.0-0.2.
  double min_view_agreement = 0.5;
};

/// The result of orient_by_propagation().
struct OrientedNormals {
  std::vector<Eigen::Vector3f> normals;  ///< one per point, consistently oriented
  std::size_t components = 0;            ///< connected components of the neighbour graph
  std::size_t flipped_by_vote = 0;       ///< normals the vote turned after propagation
  /// The side rule applied (kViewOrOutward resolved to kTowardPoint or kOutward,
  /// kAxisOrOutward to kAlongAxis or kOutward).
  ComponentSide side = ComponentSide::kOutward;
  /// kViewOrOutward / kAxisOrOutward: the agreement on facing the point / the axis that
  /// decided it (0-1).
  double view_agreement = 0.0;
};

/// Orients `normals` (one per position; unit or zero; either sign) consistently:
/// 1. the neighbour graph of `neighbours` (built over `positions`), each edge weighted
///    1 - |m_a . m_b|, where m is each normal averaged with its neighbours' as an axis (the
///    principal axis of the sum of their outer products; robust to noisy plane fits);
/// 2. its minimum spanning forest (Kruskal, most confident edges first, over one counting-sort
///    pass of the weights quantised to 2047 levels, ties in table order);
/// 3. a traversal of each tree from its seed, turning each child to agree with its parent;
/// 4. `config.vote_passes` votes (each point against the sum of n_i . n_j over its neighbours);
/// 5. each component's sign: where `fixed` flags points whose sign is known (one flag per
///    point, or empty for none), the tree starts from them and they are never turned;
///    a component without such a point is turned to `config.side` (see ComponentSide; for
///    kOutward, a closed surface's sum of n_i . (p_i - centroid) is a multiple of its enclosed
///    volume, and a cavity is found by the generalized winding number of each larger component
///    at its centroid, up to 64 components).
/// Output identical for any thread count. Parallel agreements, sort and vote; the spanning
/// forest and traversal are serial. O(n k) memory and time (plus union-find's near-constant
/// factor).
OrientedNormals orient_by_propagation(const std::vector<Eigen::Vector3f>& positions,
                                      const std::vector<Eigen::Vector3f>& normals,
                                      const NeighbourTable& neighbours,
                                      const std::vector<std::uint8_t>& fixed,
                                      const PropagationConfig& config);

}  // namespace meshflow
