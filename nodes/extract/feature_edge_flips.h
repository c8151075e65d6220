#pragma once
// The edge-flip pass of Extended Marching Cubes (Kobbelt et al. 2001, section 3.3): after
// feature cells are fanned around their feature vertices, an edge between two fans still cuts
// across the feature. Flipping it joins the two feature vertices, so triangle edges run along
// the sharp feature.

#include <cstdint>
#include <vector>

#include "runtime/triangle_mesh.h"

namespace meshflow {

/// Flips every edge (a, b) whose two triangles (a, b, f1) and (b, a, f2) have feature vertices
/// f1 != f2 opposite it (is_feature[v] != 0) into (f1, f2), when the flip is valid: neither
/// triangle was flipped already, a and b keep at least three triangles, the edge (f1, f2) does
/// not exist yet, and both new triangles have area and face the way the old pair faced.
/// Manifoldness and orientation are kept. Candidates are found in parallel and accepted in
/// edge order: deterministic. Returns the number of flips. O(T) plus a sort of the fan edges.
/// `only_between` (optional, one byte per vertex): only edges whose two ends both have a
/// non-zero byte are flipped (a stitched mesh's seam edges, the chunks having flipped theirs).
std::size_t flip_edges_between_features(TriangleMesh& mesh,
                                        const std::vector<std::uint8_t>& is_feature,
                                        const std::vector<std::uint8_t>* only_between = nullptr);

}  // namespace meshflow
