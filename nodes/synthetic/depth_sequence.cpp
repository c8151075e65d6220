#include "nodes/synthetic/depth_sequence.h"

#include <tbb/parallel_for.h>

#include <cmath>

#include <limits>
#include <string>
#include "nodes/synthetic/hashed_noise.h"

namespace meshflow::synthetic {
namespace {

class DepthSequence final : public io::Sequence {
 public:
  DepthSequence(Scene scene, DepthSequenceConfig config)
      : scene_(std::move(scene)), config_(config) {}
  std::size_t size() const override { return static_cast<std::size_t>(config_.frames); }
  io::SequenceFrame frame(std::size_t i) const override {
    const double angle = 2.0 * M_PI * static_cast<double>(i) / std::max(1, config_.frames);
    const Eigen::Vector3f eye = scene_.room.center + Eigen::Vector3f(0.2f, 0.1f, -0.1f);
    const Eigen::Vector3f target =
        eye + Eigen::Vector3f(static_cast<float>(std::cos(angle)),
                              static_cast<float>(std::sin(angle)), -0.35f);
    const Eigen::Isometry3f T_world_camera = look_at(eye, target);
    const Scene* scene = &scene_;
    const DepthSequenceConfig config = config_;
    io::SequenceFrame f;
    f.index = i;
    f.timestamp_s = static_cast<double>(i) / 30.0;
    f.name = "synthetic depth frame " + std::to_string(i);
    f.load_depth = [scene, config, T_world_camera, i] {
      DepthFrame d = render_depth(*scene, config.intrinsics, T_world_camera, config.noise_sigma,
                                  static_cast<std::uint32_t>(i + 1));
      d.timestamp_s = static_cast<double>(i) / 30.0;
      return d;
    };
    return f;
  }
  std::string description() const override {
    return "synthetic depth camera in the demo room (" + std::to_string(config_.frames) +
           " frames, " + std::to_string(config_.intrinsics.width) + "x" +
           std::to_string(config_.intrinsics.height) + ")";
  }

 private:
  Scene scene_;
  DepthSequenceConfig config_;
};

}  // namespace

Eigen::Isometry3f look_at(const Eigen::Vector3f& eye, const Eigen::Vector3f& target) {
  const Eigen::Vector3f forward = (target - eye).normalized();
  // World +z is "up"; looking straight up or down, +y takes its place.
  const Eigen::Vector3f up =
      std::abs(forward.z()) > 0.999f ? Eigen::Vector3f::UnitY() : Eigen::Vector3f::UnitZ();
  const Eigen::Vector3f right = forward.cross(up).normalized();
  const Eigen::Vector3f down = forward.cross(right);
  Eigen::Isometry3f T_world_camera = Eigen::Isometry3f::Identity();
  T_world_camera.linear().col(0) = right;
  T_world_camera.linear().col(1) = down;
  T_world_camera.linear().col(2) = forward;
  T_world_camera.translation() = eye;
  return T_world_camera;
}

DepthFrame render_rays(const PinholeIntrinsics& k, const Eigen::Isometry3f& T_world_camera,
                       float noise_sigma, std::uint32_t seed, const RayCast& cast,
                       const RayColor& color) {
  DepthFrame frame;
  frame.intrinsics = k;
  frame.T_world_camera = T_world_camera;
  frame.depth_scale = 1000.0f;
  frame.depth = Image(k.height, k.width, PixelFormat::U16);
  if (color) frame.color = Image(k.height, k.width, PixelFormat::RGB8);
  const Eigen::Matrix3f rotation = T_world_camera.linear();
  const Eigen::Vector3f eye = T_world_camera.translation();
  tbb::parallel_for(0, k.height, [&](int v) {
    auto* depth_row = frame.depth.ptr<std::uint16_t>(v);
    Rgb8* color_row = color ? frame.color.ptr<Rgb8>(v) : nullptr;
    for (int u = 0; u < k.width; ++u) {
      depth_row[u] = 0;
      if (color_row != nullptr) color_row[u] = Rgb8{};
      const Eigen::Vector3f ray_camera((static_cast<float>(u) - k.cx) / k.fx,
                                       (static_cast<float>(v) - k.cy) / k.fy, 1.0f);
      const Eigen::Vector3f dir = (rotation * ray_camera).normalized();
      const float t = cast(eye, dir);
      if (!(t >= 0.0f && t < std::numeric_limits<float>::infinity())) continue;  // a miss
      float z = t / ray_camera.norm();  // depth is the distance along the optical axis
      if (noise_sigma > 0.0f) {
        z += noise_sigma * hashed_gaussian((std::uint64_t{seed} << 40) ^
                                           (static_cast<std::uint64_t>(v) << 20) ^
                                           static_cast<std::uint64_t>(u));
      }
      depth_row[u] = static_cast<std::uint16_t>(std::clamp(std::lround(z * 1000.0f), 0L, 65535L));
      if (color_row != nullptr) color_row[u] = color(eye + t * dir, dir);
    }
  });
  return frame;
}

DepthFrame render_depth(const Scene& scene, const PinholeIntrinsics& k,
                        const Eigen::Isometry3f& T_world_camera, float noise_sigma,
                        std::uint32_t seed) {
  return render_rays(k, T_world_camera, noise_sigma, seed,
                     [&scene](const Eigen::Vector3f& eye, const Eigen::Vector3f& dir) {
                       return cast_ray(scene, eye, dir);
                     });
}

PinholeIntrinsics scaled_default_camera(int width, int height) {
  const PinholeIntrinsics standard;
  const float f = standard.fx * static_cast<float>(width) / static_cast<float>(standard.width);
  return PinholeIntrinsics{width,
                           height,
                           f,
                           f,
                           0.5f * static_cast<float>(width) - 0.5f,
                           0.5f * static_cast<float>(height) - 0.5f};
}

std::unique_ptr<io::Sequence> make_depth_sequence(const Scene& scene,
                                                  const DepthSequenceConfig& config) {
  return std::make_unique<DepthSequence>(scene, config);
}

}  // namespace meshflow::synthetic
