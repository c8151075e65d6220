#pragma once
// Solids with sharp features for extraction tests: convex polytopes (a box, a box with a
// chamfered edge), the union of two solids (concave edges) and a capped cylinder. Each gives a
// signed distance (negative inside; zero exactly on the surface) and dense surface samples with
// exact outward normals.

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "runtime/point_cloud.h"

namespace meshflow::synthetic {

/// Intersection of half-spaces n_i . p <= d_i (unit n_i), inside a sphere of radius `bound`
/// around the origin that contains it.
struct ConvexPolytope {
  std::vector<Eigen::Vector3f> normals;
  std::vector<float> offsets;
  float bound = 1.0f;
};

/// The six faces of an axis-aligned box.
ConvexPolytope box_polytope(const Eigen::Vector3f& center, const Eigen::Vector3f& half_size);

/// The box with its (+x, +y) edge cut by a 45-degree plane `chamfer` metres deep along x and y.
ConvexPolytope chamfered_box(const Eigen::Vector3f& center, const Eigen::Vector3f& half_size,
                             float chamfer);

/// A cylinder along z, capped at center.z +- half_height.
struct Cylinder {
  Eigen::Vector3f center = Eigen::Vector3f::Zero();
  float radius = 0.5f;
  float half_height = 0.5f;
};

/// A signed distance (exact on the surface and on the inner side of flat faces; elsewhere a
/// lower bound of the Euclidean distance) and surface samples with outward unit normals.
struct Solid {
  std::function<float(const Eigen::Vector3f&)> sdf;
  PointCloud samples;
};

/// Samples about `spacing` metres apart on every face (regular grids clipped to the face).
Solid make_solid(const ConvexPolytope& polytope, float spacing);
Solid make_solid(const Cylinder& cylinder, float spacing);

/// The union: sdf = min; the samples of each solid that lie outside the other.
Solid make_union(const Solid& a, const Solid& b);

}  // namespace meshflow::synthetic
