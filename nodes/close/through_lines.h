#pragma once
// Open space an observed surface shows without a sensor: the free nodes of a lattice that lie
// on a straight lattice line crossing no observed node from one face of the lattice to the
// other, where the line passes between observed walls. Such a line runs through the object
// (or past it) without meeting the surface the scan saw; where it also passes a node walled in
// by observed surface on every side across the line (an observed tunnel's inside: a
// through-hole's upper part seen from above), the line is the tunnel's continuation, and a
// fill must keep it outside (a through-hole stays open where its lower part was unseen).
// A line that only grazes an unseen patch (the lens under a sphere's unseen cap, a box's
// unseen bottom) passes no walled-in node: some ray across it leaves through the unseen patch.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace meshflow {

/// For a lattice of `size` nodes (x fastest, as DiffusionLattice) and `side` (one per node: 0
/// no data, 1 data outside the surface (distance > 0), 2 data inside): 1 for each node without
/// data that lies on a line along one of the 13 lattice directions (axes, face and body
/// diagonals) with no data anywhere on it, where that line holds a walled-in node: one from
/// which every ray along the lattice directions perpendicular to the line (6 or 8 of the 26)
/// meets data, the first it meets outside (the walls face the node with their outside: inside
/// a sphere seen in patches, the rays meet its inside first). Else 0. Parallel over lattice
/// planes or rows; the result does not depend on the thread count. O(52 x nodes) time, 12 bytes
/// a node of extra memory.
std::vector<std::uint8_t> through_line_nodes(const Eigen::Vector3i& size,
                                             const std::vector<std::uint8_t>& side);

}  // namespace meshflow
