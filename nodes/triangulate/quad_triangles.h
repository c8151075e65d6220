#pragma once
// The triangles of one 2 x 2 pixel quad: the unit of the naive depth-map triangulation, and of
// the restricted quadtree where it refines down to single pixels.

#include <cstddef>
#include <vector>

#include "nodes/triangulate/pixel_grid.h"

namespace meshflow {

/// Appends the triangles (pixel indices, counter-clockwise seen from the camera) of the quad
/// with corners (u, v) and (u + 1, v + 1): two along the shorter 3D diagonal when all four
/// pixels are valid, one when three are, none otherwise. Occlusion triangles are not tested
/// here: callers run OcclusionTriangleTest::filter over what they appended. Requires
/// 0 <= u < width - 1 and 0 <= v < height - 1. O(1).
void append_quad_triangles(const PointGrid& grid, int u, int v, std::vector<Triangle>& out);

}  // namespace meshflow
