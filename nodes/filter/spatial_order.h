#pragma once
// Points in space-filling-curve order: neighbours in space become neighbours in memory, so the
// kd-tree build, the k-nearest-neighbour queries and every pass that reads a point's neighbours
// (plane fits, orientation, interpolation, distances) touch a few cache lines instead of the
// whole cloud. Files list points in any order (sampled meshes, merged scans: often random).

#include <cstdint>
#include <vector>

#include "runtime/point_cloud.h"

namespace meshflow {

/// The permutation that lists the points of `cloud` (finite positions) along a Morton (Z-order)
/// curve over their bounding box, ties by index. Parallel, deterministic; O(n).
std::vector<std::uint32_t> morton_order(const PointCloud& cloud);

/// `cloud` with its points (and every attribute) in morton_order(); unorganized, sensor kept.
/// An organized cloud is returned unchanged (its grid is its order). O(n).
PointCloud in_morton_order(const PointCloud& cloud);

}  // namespace meshflow
