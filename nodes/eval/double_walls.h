#pragma once
// Double walls: where a mesh holds two sheets of one surface (scans of one wall meshed apart and
// laid side by side), parts of it lie close to each other in space but far apart on the mesh.

#include "runtime/triangle_mesh.h"

namespace meshflow {

/// The share (0..1) of the mesh's area within `radius` metres of another sheet facing the same
/// way: a vertex counts when a vertex within `radius` of it (straight line) whose normal (from
/// the faces' winding) is within about 45 degrees of its own is more than 3 x `radius` away
/// along the mesh's edges, or not connected to it at all; each vertex stands for a third of its
/// triangles' area. A single sheet gives 0 (small holes and folds aside), the two sides of a
/// thin wall give 0 (they face apart); two copies of one surface closer than `radius` give the
/// area of their overlap. Parallel over vertices,
/// deterministic; O(V (k log V + m log m)) for k vertices within `radius` and m within
/// 3 x `radius` along the mesh.
double double_wall_area_share(const TriangleMesh& mesh, float radius);

}  // namespace meshflow
