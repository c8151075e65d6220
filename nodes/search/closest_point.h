#pragma once
// Closest point on a triangle (Ericson, Real-Time Collision Detection, 5.1.5: Voronoi regions
// of the vertices, edges and face).

#include <Eigen/Core>

namespace meshflow {

/// The point of triangle (a, b, c) nearest to p. Degenerate triangles are handled (the result
/// lies on the segment or point they collapse to). O(1).
Eigen::Vector3f closest_point_on_triangle(const Eigen::Vector3f& p, const Eigen::Vector3f& a,
                                          const Eigen::Vector3f& b, const Eigen::Vector3f& c);

}  // namespace meshflow
