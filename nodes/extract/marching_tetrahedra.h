#pragma once
// Marching tetrahedra over a sparse grid (thesis, Wiemann 2013: the MT variant compared
// with marching cubes): every cell is split into six tetrahedra around its main diagonal
// (Kuhn/Freudenthal split), which is one global triangulation of the lattice, so tetrahedron
// faces match across cells and the surface has no ambiguous cases and no holes.

#include "nodes/extract/marching_cubes.h"

namespace meshflow {

/// Extracts the iso-surface of `field` over every cell whose 8 corners are valid. One vertex
/// per crossed lattice segment (the 12 cube edges, the 6 face diagonals and the body diagonal
/// of each cell, shared between cells), numbered in segment order; triangles wind
/// counter-clockwise seen from the positive side. Up to 12 triangles per cell (about four times
/// as many as marching cubes on planes). Parallel and deterministic; O(cells + corners).
TriangleMesh marching_tetrahedra(const SparseGrid& grid, const DistanceField& field,
                                 const ExtractConfig& config = {});

}  // namespace meshflow
