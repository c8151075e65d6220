#pragma once
// The gradient fill of the close stage (CloseFill::gradient, the default): the observed signed
// distance's gradient (the surface's normal field, unit length in the band around the data) is
// spread into the unobserved nodes by volumetric diffusion, and the distance of those nodes is
// the potential whose gradient fits that field best (the Poisson equation lap u = div g, the
// observed nodes held at their distances). Where the data stops, the surface goes on the way it
// was heading: a sphere's unseen cap curves on, a box's unseen bottom closes where the walls'
// fields meet the top's, an unseen patch of a torus follows its tube. Diffusing the distance
// itself (CloseFill::diffusion) cannot: a harmonic fill lies between its boundary values, so the
// inside of an object seen only in a thin band stays near zero and the lattice's outside faces
// pull the surface into a deep dome.
//
// The field is smooth where there is no data, so it is diffused on a lattice of every second
// node (an eighth of the nodes); only the potential is solved at full resolution.

#include <array>
#include <cstdint>
#include <vector>

#include "nodes/close/volume_diffusion.h"

namespace meshflow {

/// Replaces the values of the free nodes of `l` (l.source must be empty) by the potential of the
/// diffused gradient of the observed nodes' distances (file comment). `observed` (one per node)
/// marks the nodes with data; `voxel` is the lattice spacing in metres, the values' unit. The
/// gradient is taken at observed nodes off the lattice's faces with an observed neighbour along
/// each axis (central differences where both are), averaged onto every second node from it and
/// its 6 neighbours, diffused there with config's levels and half its sweeps per level
/// (the half-resolution lattice's faces are free: the field goes on past the data); u solves
/// sum over the 6 neighbours j of (u_i - u_j) = -voxel x div g_i at the free nodes with config's
/// levels and a quarter of its sweeps per level. Held nodes keep their values. Returns the
/// levels of the potential's solve. Parallel over planes; the result does not depend on the
/// thread count. Time O(nodes x sweeps_per_level / 4) (the field's three solves on an eighth of
/// the nodes cost about 40 % of the potential's); extra memory about 10 bytes a node.
/// Per side of `l` (-x, +x, -y, +y, -z, +z): how far, in nodes, past the data's box (the plane
/// `margin` nodes inside that face) the observed surface would close by its own turn. Over the
/// observed nodes within a voxel of the surface and within `window` nodes of that plane, the
/// unit normal's component c along the side's outward axis is fitted as c0 + s h (h: nodes from
/// the plane, least squares): a surface turning to face the side (s < 0, c0 > 0), as a sphere's
/// or a tube's underside does, faces it at h = -(1 - c0) / s, on a circle of its curvature -s;
/// the reach is that depth, 0 where the surface already faces the side, and infinite where it
/// does not turn (a box's walls) or too few nodes fit. Parallel over planes; the result does not
/// depend on the thread count. O(nodes).
std::array<float, 6> gradient_fill_reach(const DiffusionLattice& l,
                                         const std::vector<std::uint8_t>& observed, float voxel,
                                         int margin, int window);

int gradient_fill(DiffusionLattice& l, const std::vector<std::uint8_t>& observed, float voxel,
                  const DiffusionConfig& config = {});

}  // namespace meshflow
