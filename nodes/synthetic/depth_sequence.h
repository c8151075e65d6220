#pragma once
// A synthetic depth camera moving through the analytic demo room: ray-cast depth images with
// exact poses, the ground truth for the depth path and `meshflow run --synthetic-depth`.

#include <functional>
#include <memory>

#include "nodes/io/sequence.h"
#include "nodes/synthetic/scan_simulator.h"
#include "runtime/depth_frame.h"

namespace meshflow::synthetic {

/// Camera pose looking from `eye` towards `target` with world +z up (+y when looking straight
/// up or down), in meshflow's camera convention (x right, y down, z forward).
Eigen::Isometry3f look_at(const Eigen::Vector3f& eye, const Eigen::Vector3f& target);

/// Distance along the unit world-frame ray from `eye` in direction `dir` to the first surface,
/// metres; infinity or a negative number on a miss. Called from several threads at once.
using RayCast = std::function<float(const Eigen::Vector3f& eye, const Eigen::Vector3f& dir)>;
/// The colour seen where a ray in direction `dir` hits the point `hit`.
using RayColor = std::function<Rgb8(const Eigen::Vector3f& hit, const Eigen::Vector3f& dir)>;

/// One ray per pixel through `cast`: U16 depth in millimetres (depth_scale 1000, 0 where the ray
/// misses), plus Gaussian range noise of `noise_sigma` metres (hash of seed and pixel, so
/// deterministic for any thread count); with `color`, an RGB8 image of color() at each hit
/// (black where the ray misses). The renderer shared by render_depth() and
/// render_object_depth(). Parallel over rows.
DepthFrame render_rays(const PinholeIntrinsics& intrinsics, const Eigen::Isometry3f& T_world_camera,
                       float noise_sigma, std::uint32_t seed, const RayCast& cast,
                       const RayColor& color = nullptr);

/// Ray-casts `scene` through every pixel (render_rays() with cast_ray()): U16 depth in
/// millimetres, no colour. Parallel over rows.
DepthFrame render_depth(const Scene& scene, const PinholeIntrinsics& intrinsics,
                        const Eigen::Isometry3f& T_world_camera, float noise_sigma = 0.0f,
                        std::uint32_t seed = 1);

/// The default camera (640 x 480, f = 525) at another image size: the focal length scales with
/// the width (same field of view), the principal point is the image centre. O(1).
PinholeIntrinsics scaled_default_camera(int width, int height);

struct DepthSequenceConfig {
  int frames = 8;
  PinholeIntrinsics intrinsics;  ///< 640 x 480, f = 525 by default
  float noise_sigma = 0.001f;    ///< metres
};

/// The camera turns on the spot at the room's centre, one frame per 1/frames of a full turn,
/// looking slightly down at the walls and furniture.
std::unique_ptr<io::Sequence> make_depth_sequence(const Scene& scene,
                                                  const DepthSequenceConfig& config = {});

}  // namespace meshflow::synthetic
