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

struct PropagationConfig {
  /// Passes of a final vote in which a normal that disagrees with the confidence-weighted
  /// majority of its neighbours is turned over (0 = off). Repairs single points that the tree
  /// reached through a poor edge.
  int vote_passes = 2;
};

/// The result of orient_by_propagation().
struct OrientedNormals {
  std::vector<Eigen::Vector3f> normals;  ///< one per point, consistently oriented
  std::size_t components = 0;            ///< connected components of the neighbour graph
  std::size_t flipped_by_vote = 0;       ///< normals the vote turned after propagation
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
///    a component without such a point is turned outward, i.e. so that the sum of
///    n_i . (p_i - centroid) over its points is positive (for a closed surface that sum is a
///    multiple of the enclosed volume); where that sum is indecisive (an open, flat piece), so
///    that the normal of its point of largest x has a non-negative x; a component inside an odd
///    number of larger ones (a cavity's wall, a hollow ball's inner shell: the generalized
///    winding number of each larger one at its centroid) then faces inward, towards the
///    cavity (up to 64 components).
/// Output identical for any thread count. Parallel agreements, sort and vote; the spanning
/// forest and traversal are serial. O(n k) memory and time (plus union-find's near-constant
/// factor).
OrientedNormals orient_by_propagation(const std::vector<Eigen::Vector3f>& positions,
                                      const std::vector<Eigen::Vector3f>& normals,
                                      const NeighbourTable& neighbours,
                                      const std::vector<std::uint8_t>& fixed,
                                      const PropagationConfig& config);

}  // namespace meshflow
