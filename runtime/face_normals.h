#pragma once
// The unit normals of all faces of a mesh at once, for passes that read every face's normal
// several times (the feature detection reads each from its three corners).

#include <Eigen/Core>
#include <vector>

#include "runtime/triangle_mesh.h"

namespace meshflow {

/// Per triangle t: (n, w) with n bit for bit face_normal(mesh, t) (the same float operations in
/// the same order, eight faces per vector) and w = 1 where n is non-zero, 0 where it is zero (a
/// face without area, or with a coordinate that is not finite): summed over a vertex's faces,
/// the fourth lane counts those with a normal. 16-byte rows, one vector load each. Corners must
/// index vertices. Parallel over blocks of faces; the values do not depend on the thread count.
/// O(T).
std::vector<Eigen::Vector4f> counted_face_normals(const TriangleMesh& mesh);

}  // namespace meshflow
