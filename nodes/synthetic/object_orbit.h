#pragma once
// A synthetic depth camera circling one of the closed test objects (closed_objects.h): ray-cast
// depth images with exact poses, so fused maps can be measured against the object's exact
// surface (accuracy and completeness) — the object-scanning counterpart of depth_sequence.h.

#include <memory>

#include "nodes/io/sequence.h"
#include "nodes/synthetic/closed_objects.h"
#include "runtime/depth_frame.h"

namespace meshflow::synthetic {

/// Ray-casts `object` through every pixel by sphere tracing its exact distance: U16 depth in
/// millimetres (depth_scale 1000, 0 where the ray misses), plus Gaussian range noise of
/// `noise_sigma` metres (hash of seed and pixel: deterministic for any thread count). Also an
/// RGB8 colour image shading the surface by its normal (black where the ray misses); through
/// render_rays(). Parallel over rows; O(pixels x steps x patches).
DepthFrame render_object_depth(const ClosedObject& object, const PinholeIntrinsics& intrinsics,
                               const Eigen::Isometry3f& T_world_camera, float noise_sigma = 0.0f,
                               std::uint32_t seed = 1);

struct ObjectOrbitConfig {
  int frames = 24;
  PinholeIntrinsics intrinsics;  ///< 640 x 480, f = 525 by default
  float noise_sigma = 0.001f;    ///< metres
};

/// Camera poses circling the object: half the frames on a ring 30 degrees above its centre, half
/// on a ring 30 degrees below (interleaved, so any prefix sees both sides), at a distance where
/// the object fills about 70 % of the image height, always looking at its centre.
std::vector<Eigen::Isometry3f> object_orbit_poses(const ClosedObject& object,
                                                  const ObjectOrbitConfig& config);

/// The frames of object_orbit_poses(), rendered on demand by render_object_depth().
std::unique_ptr<io::Sequence> make_object_orbit(const ClosedObject& object,
                                                const ObjectOrbitConfig& config = {});

}  // namespace meshflow::synthetic
