#pragma once
// Open space an observed surface shows without a sensor: the free nodes of a lattice that lie
// on a straight lattice line crossing no observed node from one face of the lattice to the
// other, where the line passes between observed walls. Such a line runs through the object
// (or past it) without meeting the surface the scan saw; where it also passes a node walled in
// by observed surface on every side across the line (an observed tunnel's inside: a
// through-hole's upper part seen from above), the line is the tunnel's continuation, and a
// fill must keep it outside (a through-hole stays open where its lower part was unseen). A
// tunnel is walled in for several nodes in a row along its line; one walled node is a slit in
// a thin band (two patches nearly meeting) and opens nothing. A diagonal step passes the nodes
// between its ends too, so no ray or line slips between the nodes of a band one node thick.
// A line that only grazes an unseen patch (the lens under a sphere's unseen cap, a box's
// unseen bottom) passes no walled-in node: some ray across it leaves through the unseen patch.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace meshflow {

/// For a lattice of `size` nodes (x fastest, as DiffusionLattice) and `side` (one per node: 0
/// no data, 1 data outside the surface (distance > 0), 2 data inside): 1 for each node without
/// data that lies on a line along one of the 13 lattice directions (axes, face and body
/// diagonals) with no data anywhere on it, where that line holds three walled-in nodes in a
/// row: nodes from which every ray along the lattice directions perpendicular to the line (6 or
/// 8 of the 26) meets data, the first it meets outside (the walls face the node with their
/// outside: inside a sphere seen in patches, the rays meet its inside first). A ray's or line's
/// step from node q to q + d meets the data of the nodes q + s, s being d with some of its
/// components zeroed, the nearest (fewest components) first, inside winning among equals; then
/// q + d. Else 0. Parallel over lattice planes or rows; the result does not depend on the
/// thread count. O(230 x nodes) time, 13 bytes a node of extra memory.
std::vector<std::uint8_t> through_line_nodes(const Eigen::Vector3i& size,
                                             const std::vector<std::uint8_t>& side);

}  // namespace meshflow
