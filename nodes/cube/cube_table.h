#pragma once
// Marching-cubes case table, generated (not transcribed) from the cube's topology.
//
// For each of the 256 inside/outside corner patterns, the iso-contour is traced on each of the
// six faces (on a face with two diagonal inside corners, the outside corners are separated;
// the rule depends only on the face's own corners, so neighbouring cells always agree and the
// surface has no cracks), the face segments are chained into closed loops around the cube, and
// each loop is fan-triangulated. Triangles wind counter-clockwise seen from the outside
// (where the field is >= iso). Every case yields a closed, consistently oriented surface patch.

#include <array>
#include <cstdint>
#include <vector>

namespace meshflow {

/// Corner c of a cube is at (c & 1, (c >> 1) & 1, (c >> 2) & 1).
/// Edge e joins corners kCubeEdges[e][0] < kCubeEdges[e][1] along axis kCubeEdgeAxis[e].
constexpr std::array<std::array<int, 2>, 12> kCubeEdges = {{{0, 1},
                                                            {2, 3},
                                                            {4, 5},
                                                            {6, 7},
                                                            {0, 2},
                                                            {1, 3},
                                                            {4, 6},
                                                            {5, 7},
                                                            {0, 4},
                                                            {1, 5},
                                                            {2, 6},
                                                            {3, 7}}};
constexpr std::array<int, 12> kCubeEdgeAxis = {0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2};

/// Triangles of one case as triples of cube edge indices.
struct CubeCase {
  std::vector<std::array<std::uint8_t, 3>> triangles;
  /// The closed iso-contours the triangles fill, as cube edges in order, clockwise seen from
  /// outside (so a fan (apex, loop[k + 1], loop[k]) winds counter-clockwise). A loop of n
  /// edges owns the next n - 2 entries of `triangles`, loops in order.
  std::vector<std::vector<std::uint8_t>> loops;
};

/// The 256 cases, indexed by the pattern with bit c set when corner c is inside (< iso).
/// Built once on first use (thread-safe static initialization).
const std::array<CubeCase, 256>& cube_cases();

}  // namespace meshflow
