#include "nodes/synthetic/object_orbit.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "nodes/synthetic/depth_sequence.h"

namespace meshflow::synthetic {
namespace {

constexpr float kHitDistance = 1e-5f;  // metres: sphere tracing stops this close to the surface
constexpr int kMaxSteps = 256;         // grazing rays that have not converged count as misses

// Distance along the unit ray from `eye` to the object's surface, or a negative number when it
// misses: sphere tracing from where the ray enters the object's bounding sphere.
float trace(const ClosedObject& object, const Eigen::Vector3f& eye, const Eigen::Vector3f& dir) {
  const Eigen::Vector3f center = object.bounds.center();
  const float radius = 0.5f * object.diagonal() + 1e-3f;
  const Eigen::Vector3f to_center = center - eye;
  const float along = to_center.dot(dir);
  const float miss2 = to_center.squaredNorm() - along * along;
  if (miss2 > radius * radius) return -1.0f;
  const float half_chord = std::sqrt(radius * radius - miss2);
  const float exit = along + half_chord;
  float t = std::max(0.0f, along - half_chord);
  for (int step = 0; step < kMaxSteps && t <= exit; ++step) {
    const float d = object.distance(eye + t * dir);
    if (d < kHitDistance) return t;
    t += d;
  }
  return -1.0f;
}

// Outward unit normal near a surface point seen along `dir`: the gradient of the distance at a
// point just in front of the surface (central differences).
Eigen::Vector3f outward_normal(const ClosedObject& object, const Eigen::Vector3f& hit,
                               const Eigen::Vector3f& dir) {
  const Eigen::Vector3f p = hit - 1e-3f * dir;
  constexpr float kStep = 1e-4f;
  Eigen::Vector3f g;
  for (int axis = 0; axis < 3; ++axis) {
    Eigen::Vector3f e = Eigen::Vector3f::Zero();
    e[axis] = kStep;
    g[axis] = object.distance(p + e) - object.distance(p - e);
  }
  return g.norm() > 0.0f ? Eigen::Vector3f(g.normalized()) : Eigen::Vector3f(-dir);
}

std::uint8_t shade(float n) { return static_cast<std::uint8_t>(std::lround(127.5f * (n + 1.0f))); }

class ObjectOrbit final : public io::Sequence {
 public:
  ObjectOrbit(ClosedObject object, ObjectOrbitConfig config)
      : object_(std::move(object)), config_(config), poses_(object_orbit_poses(object_, config_)) {}
  std::size_t size() const override { return poses_.size(); }
  io::SequenceFrame frame(std::size_t i) const override {
    io::SequenceFrame f;
    f.index = i;
    f.timestamp_s = static_cast<double>(i) / 30.0;
    f.name = "synthetic " + object_.name + " orbit frame " + std::to_string(i);
    f.load_depth = [this, i] {
      DepthFrame d = render_object_depth(object_, config_.intrinsics, poses_[i],
                                         config_.noise_sigma, static_cast<std::uint32_t>(i + 1));
      d.timestamp_s = static_cast<double>(i) / 30.0;
      return d;
    };
    return f;
  }
  std::string description() const override {
    return "synthetic depth camera circling the " + object_.name + " (" +
           std::to_string(poses_.size()) + " frames, " + std::to_string(config_.intrinsics.width) +
           "x" + std::to_string(config_.intrinsics.height) + ")";
  }

 private:
  ClosedObject object_;
  ObjectOrbitConfig config_;
  std::vector<Eigen::Isometry3f> poses_;
};

}  // namespace

DepthFrame render_object_depth(const ClosedObject& object, const PinholeIntrinsics& k,
                               const Eigen::Isometry3f& T_world_camera, float noise_sigma,
                               std::uint32_t seed) {
  return render_rays(
      k, T_world_camera, noise_sigma, seed,
      [&object](const Eigen::Vector3f& eye, const Eigen::Vector3f& dir) {
        return trace(object, eye, dir);
      },
      [&object](const Eigen::Vector3f& hit, const Eigen::Vector3f& dir) {
        const Eigen::Vector3f n = outward_normal(object, hit, dir);
        return Rgb8{shade(n.x()), shade(n.y()), shade(n.z())};
      });
}

std::vector<Eigen::Isometry3f> object_orbit_poses(const ClosedObject& object,
                                                  const ObjectOrbitConfig& config) {
  const PinholeIntrinsics& k = config.intrinsics;
  const float half_fov = std::atan(0.5f * static_cast<float>(std::min(k.width, k.height)) / k.fy);
  const float distance = 0.5f * object.diagonal() / std::tan(0.7f * half_fov);
  const Eigen::Vector3f center = object.bounds.center();
  const float elevation = static_cast<float>(M_PI) / 6.0f;
  std::vector<Eigen::Isometry3f> poses;
  const int frames = std::max(1, config.frames);
  for (int i = 0; i < frames; ++i) {
    const float azimuth =
        2.0f * static_cast<float>(M_PI) * static_cast<float>(i) / static_cast<float>(frames);
    const float up = (i % 2 == 0 ? 1.0f : -1.0f) * elevation;
    const Eigen::Vector3f eye =
        center + distance * Eigen::Vector3f(std::cos(up) * std::cos(azimuth),
                                            std::cos(up) * std::sin(azimuth), std::sin(up));
    poses.push_back(look_at(eye, center));
  }
  return poses;
}

std::unique_ptr<io::Sequence> make_object_orbit(const ClosedObject& object,
                                                const ObjectOrbitConfig& config) {
  return std::make_unique<ObjectOrbit>(object, config);
}

}  // namespace meshflow::synthetic
