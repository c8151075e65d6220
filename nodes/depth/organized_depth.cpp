#include "nodes/depth/organized_depth.h"

#include <cmath>
#include <cstddef>

namespace meshflow {
namespace {

constexpr std::size_t kMinValidPoints = 16;

// Least-squares line pixel = focal * slope + centre over (slope, pixel) pairs, from centred sums
// (no cancellation between large sums).
struct LineFit {
  double n = 0, mean_slope = 0, mean_pixel = 0, slope_slope = 0, slope_pixel = 0;
  void add_mean(double slope, double pixel) {
    n += 1;
    mean_slope += slope;
    mean_pixel += pixel;
  }
  void finish_means() {
    mean_slope /= n;
    mean_pixel /= n;
  }
  void add_centred(double slope, double pixel) {
    const double ds = slope - mean_slope;
    slope_slope += ds * ds;
    slope_pixel += ds * (pixel - mean_pixel);
  }
  double focal() const { return slope_pixel / slope_slope; }
  double centre() const { return mean_pixel - focal() * mean_slope; }
};

}  // namespace

std::optional<DepthFrame> depth_frame_from_organized(const PointCloud& cloud,
                                                     double max_residual_px) {
  if (!cloud.is_organized() || cloud.width > 65535 || cloud.height > 65535) return std::nullopt;
  const Eigen::Vector3f origin =
      cloud.has_sensor_origin ? cloud.sensor_origin : Eigen::Vector3f::Zero();
  if (!origin.allFinite()) return std::nullopt;
  const std::size_t w = cloud.width, h = cloud.height;
  // Visits every valid pixel (u, v) with its sensor-frame point; false if a finite point is
  // not in front of the sensor.
  auto for_each_valid = [&](auto&& fn) {
    for (std::size_t v = 0; v < h; ++v)
      for (std::size_t u = 0; u < w; ++u) {
        const Eigen::Vector3f& p = cloud.positions[v * w + u];
        if (!p.allFinite()) continue;
        const Eigen::Vector3d q = (p - origin).cast<double>();
        if (!(q.z() > 0.0)) return false;
        fn(u, v, q);
      }
    return true;
  };
  LineFit fit_u, fit_v;
  const bool in_front = for_each_valid([&](std::size_t u, std::size_t v, const Eigen::Vector3d& q) {
    fit_u.add_mean(q.x() / q.z(), static_cast<double>(u));
    fit_v.add_mean(q.y() / q.z(), static_cast<double>(v));
  });
  if (!in_front || fit_u.n < kMinValidPoints) return std::nullopt;
  fit_u.finish_means();
  fit_v.finish_means();
  for_each_valid([&](std::size_t u, std::size_t v, const Eigen::Vector3d& q) {
    fit_u.add_centred(q.x() / q.z(), static_cast<double>(u));
    fit_v.add_centred(q.y() / q.z(), static_cast<double>(v));
  });
  const double fx = fit_u.focal(), fy = fit_v.focal(), cx = fit_u.centre(), cy = fit_v.centre();
  if (!(fx > 1e-3 && fx < 1e6 && fy > 1e-3 && fy < 1e6 && std::abs(cx) < 1e6 && std::abs(cy) < 1e6))
    return std::nullopt;
  const double limit2 = max_residual_px * max_residual_px;
  bool fits = true;
  for_each_valid([&](std::size_t u, std::size_t v, const Eigen::Vector3d& q) {
    const double du = fx * q.x() / q.z() + cx - static_cast<double>(u);
    const double dv = fy * q.y() / q.z() + cy - static_cast<double>(v);
    fits = fits && du * du + dv * dv <= limit2;
  });
  if (!fits) return std::nullopt;

  DepthFrame frame;
  frame.intrinsics =
      PinholeIntrinsics{static_cast<int>(w),    static_cast<int>(h),    static_cast<float>(fx),
                        static_cast<float>(fy), static_cast<float>(cx), static_cast<float>(cy)};
  frame.depth = Image(static_cast<int>(h), static_cast<int>(w), PixelFormat::F32);
  frame.depth_scale = 1.0f;
  const bool colored = cloud.colors.size() == cloud.positions.size();
  if (colored) frame.color = Image(static_cast<int>(h), static_cast<int>(w), PixelFormat::RGB8);
  for (std::size_t v = 0; v < h; ++v)
    for (std::size_t u = 0; u < w; ++u) {
      const std::size_t i = v * w + u;
      const Eigen::Vector3f& p = cloud.positions[i];
      if (p.allFinite())
        frame.depth.at<float>(static_cast<int>(v), static_cast<int>(u)) = p.z() - origin.z();
      if (colored) {
        frame.color.at<Rgb8>(static_cast<int>(v), static_cast<int>(u)) = cloud.colors[i];
      }
    }
  frame.T_world_camera.translation() = origin;
  return frame;
}

}  // namespace meshflow
