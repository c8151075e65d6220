#include "nodes/synthetic/object_scan.h"

#include <cmath>
#include <random>

#include "nodes/synthetic/depth_sequence.h"
#include "nodes/synthetic/object_orbit.h"

namespace meshflow::synthetic {

ObjectScan scan_object(const ClosedObject& object, const ObjectScanConfig& config) {
  const PinholeIntrinsics k = scaled_default_camera(config.width, config.height);
  const float half_fov = std::atan(0.5f * static_cast<float>(std::min(k.width, k.height)) / k.fy);
  const float distance = 0.5f * object.diagonal() / std::tan(0.7f * half_fov);
  const Eigen::Vector3f center = object.bounds.center();
  const float up = config.elevation_deg * static_cast<float>(M_PI) / 180.0f;
  ObjectScan scan;
  scan.intrinsics = k;
  const int views = std::max(1, config.views);
  for (int i = 0; i < views; ++i) {
    const float azimuth =
        2.0f * static_cast<float>(M_PI) * static_cast<float>(i) / static_cast<float>(views);
    const Eigen::Vector3f eye =
        center + distance * Eigen::Vector3f(std::cos(up) * std::cos(azimuth),
                                            std::cos(up) * std::sin(azimuth), std::sin(up));
    const Eigen::Isometry3f pose = look_at(eye, center);
    const DepthFrame d = render_object_depth(object, k, pose, config.noise_sigma,
                                             config.seed * 1000u + static_cast<std::uint32_t>(i));
    scan.sensors.push_back(eye);
    scan.poses.push_back(pose);
    scan.first_of_view.push_back(static_cast<std::uint32_t>(scan.cloud.size()));
    for (int v = 0; v < k.height; ++v) {
      for (int u = 0; u < k.width; ++u) {
        const std::uint16_t raw = d.depth.at<std::uint16_t>(v, u);
        if (raw == 0) continue;
        const float z = static_cast<float>(raw) / d.depth_scale;
        const Eigen::Vector3f p_camera((static_cast<float>(u) - k.cx) * z / k.fx,
                                       (static_cast<float>(v) - k.cy) * z / k.fy, z);
        scan.cloud.positions.push_back(pose * p_camera);
      }
    }
  }
  scan.first_of_view.push_back(static_cast<std::uint32_t>(scan.cloud.size()));
  const std::size_t surface = scan.cloud.size();
  scan.outliers = static_cast<std::size_t>(
      std::lround(static_cast<double>(config.outlier_fraction) * static_cast<double>(surface)));
  const Eigen::Vector3f lo = object.bounds.min() - 0.05f * object.bounds.sizes();
  const Eigen::Vector3f size = 1.1f * object.bounds.sizes();
  std::mt19937_64 rng(config.seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (std::size_t i = 0; i < scan.outliers; ++i) {
    const float x = unit(rng), y = unit(rng), z = unit(rng);
    scan.cloud.positions.push_back(lo + Eigen::Vector3f(x, y, z).cwiseProduct(size));
  }
  return scan;
}

}  // namespace meshflow::synthetic
