#pragma once
// Closed test objects of the kind users scan without a sensor (parts, CAD checks): a sphere, a
// torus, an L-shaped prism, a cube with a chamfered edge and a box with a cylindrical
// through-hole. Each gives the exact distance to its surface (the ground truth of accuracy
// tests) and points drawn uniformly by area over it, with exact outward normals.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "runtime/point_cloud.h"

namespace meshflow::synthetic {

/// One piece of an object's surface: its area, a uniform sampler and the exact distance to it.
struct SurfacePatch {
  double area = 0.0;  ///< m^2
  /// Draws one point uniformly over the patch with its outward unit normal.
  std::function<void(std::mt19937_64& rng, Eigen::Vector3f& point, Eigen::Vector3f& normal)> draw;
  /// Exact Euclidean distance from a point to the patch, metres.
  std::function<float(const Eigen::Vector3f&)> distance;
};

/// A closed surface made of patches that meet only along their borders.
struct ClosedObject {
  std::string name;
  std::vector<SurfacePatch> patches;
  Eigen::AlignedBox3f bounds;  ///< axis-aligned bounding box of the surface
  /// Sharp edges (segments where faces meet at an angle) and corners of polyhedral objects,
  /// for measuring how well extraction keeps features; empty for smooth ones.
  std::vector<std::pair<Eigen::Vector3f, Eigen::Vector3f>> feature_edges;
  std::vector<Eigen::Vector3f> corners;

  /// Exact distance from p to the surface (minimum over the patches), metres. O(patches).
  float distance(const Eigen::Vector3f& p) const;
  /// Total area, m^2.
  double area() const;
  /// Length of the bounding box's diagonal, metres.
  float diagonal() const { return bounds.sizes().norm(); }
  /// `count` points uniformly distributed by area, each moved by isotropic Gaussian noise of
  /// `noise_sigma` metres, with exact outward normals (of the point before the noise).
  /// Deterministic for a given seed. Serial, O(count).
  PointCloud sample(std::size_t count, float noise_sigma, std::uint32_t seed) const;
};

ClosedObject sphere_object();          ///< radius 0.5 m
ClosedObject torus_object();           ///< radii 0.4 m and 0.15 m, axis z
ClosedObject l_shape_object();         ///< L-shaped prism 0.8 x 0.8 x 0.3 m, arms 0.3 m wide
ClosedObject chamfered_cube_object();  ///< 0.6 m cube, one edge cut 0.15 m deep at 45 degrees
ClosedObject box_with_hole_object();   ///< 0.8 x 0.8 x 0.4 m box, a 0.15 m-radius hole along z
ClosedObject box_object();             ///< 0.8 x 0.6 x 0.5 m box
/// A 0.6 x 0.4 m plate 0.02 m thick: thinner than a TSDF's usual truncation band at 1 cm voxels,
/// the hard case of fusing views from both sides.
ClosedObject thin_plate_object();

/// The six objects above before the plate, in that order (the held-out-style accuracy set).
std::vector<ClosedObject> closed_test_objects();

/// closed_test_objects() and the thin plate.
std::vector<ClosedObject> all_test_objects();

/// The object of all_test_objects() called `name` ("sphere", "torus", "l-shape",
/// "chamfered-cube", "box-with-hole", "box", "thin-plate"), or nullopt.
std::optional<ClosedObject> closed_test_object(const std::string& name);

}  // namespace meshflow::synthetic
