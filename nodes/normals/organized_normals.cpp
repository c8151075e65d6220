#include "nodes/normals/organized_normals.h"

#include <tbb/parallel_for.h>

#include <limits>

namespace meshflow {

PointCloud back_project(const DepthFrame& frame, const cv::Mat& depth_m) {
  const PinholeIntrinsics& k = frame.intrinsics;
  const int w = depth_m.cols, h = depth_m.rows;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const Eigen::Vector3f kNaN = Eigen::Vector3f::Constant(nan);
  std::vector<Eigen::Vector3f> camera(static_cast<std::size_t>(w) * static_cast<std::size_t>(h),
                                      kNaN);
  tbb::parallel_for(0, h, [&](int v) {
    for (int u = 0; u < w; ++u) {
      const float d = depth_m.at<float>(v, u);
      if (d > 0.0f) {
        camera[static_cast<std::size_t>(v * w + u)] = {(static_cast<float>(u) - k.cx) * d / k.fx,
                                                       (static_cast<float>(v) - k.cy) * d / k.fy,
                                                       d};
      }
    }
  });
  PointCloud cloud;
  cloud.width = static_cast<std::uint32_t>(w);
  cloud.height = static_cast<std::uint32_t>(h);
  cloud.positions.assign(camera.size(), kNaN);
  cloud.normals.assign(camera.size(), kNaN);
  const bool color =
      !frame.color.empty() && frame.color.size() == depth_m.size() && frame.color.type() == CV_8UC3;
  if (color) cloud.colors.resize(camera.size());
  const Eigen::Matrix3f rotation = frame.T_world_camera.linear();
  tbb::parallel_for(0, h, [&](int v) {
    auto at = [&](int x, int y) -> const Eigen::Vector3f* {
      if (x < 0 || y < 0 || x >= w || y >= h) return nullptr;
      const Eigen::Vector3f& p = camera[static_cast<std::size_t>(y * w + x)];
      return p.allFinite() ? &p : nullptr;
    };
    for (int u = 0; u < w; ++u) {
      const std::size_t i = static_cast<std::size_t>(v * w + u);
      const Eigen::Vector3f* c = at(u, v);
      if (c == nullptr) continue;
      const Eigen::Vector3f *l = at(u - 1, v), *r = at(u + 1, v), *up = at(u, v - 1),
                            *dn = at(u, v + 1);
      if ((l == nullptr && r == nullptr) || (up == nullptr && dn == nullptr)) continue;
      const Eigen::Vector3f dx = (r ? *r : *c) - (l ? *l : *c);
      const Eigen::Vector3f dy = (dn ? *dn : *c) - (up ? *up : *c);
      Eigen::Vector3f n = dx.cross(dy);
      const float len = n.norm();
      if (!(len > 0.0f)) continue;
      n /= len;
      if (n.dot(-*c) < 0.0f) n = -n;  // towards the camera at the origin
      cloud.positions[i] = frame.T_world_camera * *c;
      cloud.normals[i] = rotation * n;
      if (color) {
        const cv::Vec3b rgb = frame.color.at<cv::Vec3b>(v, u);
        cloud.colors[i] = Rgb8{rgb[0], rgb[1], rgb[2]};
      }
    }
  });
  cloud.sensor_origin = frame.T_world_camera.translation();
  cloud.has_sensor_origin = true;
  return cloud;
}

}  // namespace meshflow
