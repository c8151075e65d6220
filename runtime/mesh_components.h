#pragma once
// Connected components of a mesh's triangles, labelled per vertex in parallel.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "runtime/triangle_mesh.h"

namespace meshflow {

/// Per vertex of `vertex_count`, the lowest vertex index of its connected component, vertices
/// joined through the triangles that hold them (a vertex no triangle holds is its own
/// component; corners indexing no vertex are left out): the labels DisjointSets gives after
/// uniting every triangle's corners, for any thread count. A concurrent union-find over triangle
/// ranges: roots are linked by compare-and-swap, always the larger under the smaller, so each
/// set's root is its lowest index whatever the order of the links. Thread-safe (reads
/// `triangles` only). O(T alpha + V) work, parallel.
std::vector<std::uint32_t> vertex_component_labels(const std::vector<Triangle>& triangles,
                                                   std::size_t vertex_count);

}  // namespace meshflow
