#include "nodes/normals/organized_normals.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <vector>

#include "runtime/parallel.h"

namespace meshflow {
namespace {

// Back-projects pixels of a metric depth image on the fly (no intermediate camera-frame image:
// a point is three multiplications, cheaper than the memory traffic of storing it).
class PixelSurface {
 public:
  PixelSurface(const DepthFrame& frame, const Image& depth_m)
      : depth_(depth_m),
        T_world_camera_(frame.T_world_camera),
        rotation_(frame.T_world_camera.linear()),
        ray_x_(static_cast<std::size_t>(depth_m.cols())),
        ray_y_(static_cast<std::size_t>(depth_m.rows())) {
    const PinholeIntrinsics& k = frame.intrinsics;
    for (int u = 0; u < depth_m.cols(); ++u)
      ray_x_[static_cast<std::size_t>(u)] = (static_cast<float>(u) - k.cx) / k.fx;
    for (int v = 0; v < depth_m.rows(); ++v)
      ray_y_[static_cast<std::size_t>(v)] = (static_cast<float>(v) - k.cy) / k.fy;
  }

  // World-frame point and camera-facing normal of pixel (u, v); false if the pixel has no depth
  // or lacks a valid neighbour in both image directions.
  inline bool at(int u, int v, Eigen::Vector3f& position, Eigen::Vector3f& normal) const {
    const float* row = depth_.ptr<float>(v);
    const float* above = v > 0 ? depth_.ptr<float>(v - 1) : nullptr;
    const float* below = v + 1 < depth_.rows() ? depth_.ptr<float>(v + 1) : nullptr;
    const float ry = ray_y_[static_cast<std::size_t>(v)];
    Eigen::Vector3f c, l, r, up, dn;
    if (!point(row, u, ry, c)) return false;
    const bool has_l = u > 0 && point(row, u - 1, ry, l);
    const bool has_r = u + 1 < depth_.cols() && point(row, u + 1, ry, r);
    const bool has_up =
        above != nullptr && point(above, u, ray_y_[static_cast<std::size_t>(v - 1)], up);
    const bool has_dn =
        below != nullptr && point(below, u, ray_y_[static_cast<std::size_t>(v + 1)], dn);
    if ((!has_l && !has_r) || (!has_up && !has_dn)) return false;
    const Eigen::Vector3f dx = (has_r ? r : c) - (has_l ? l : c);
    const Eigen::Vector3f dy = (has_dn ? dn : c) - (has_up ? up : c);
    Eigen::Vector3f n = dx.cross(dy);
    const float len = n.norm();
    if (!(len > 0.0f)) return false;
    n /= len;
    if (n.dot(-c) < 0.0f) n = -n;  // towards the camera at the origin
    position = T_world_camera_ * c;
    normal = rotation_ * n;
    return true;
  }

 private:
  // Camera-frame point of pixel u of a depth row whose ray y-slope is `ry`; false without depth.
  inline bool point(const float* row, int u, float ry, Eigen::Vector3f& p) const {
    const float d = row[u];
    if (!(d > 0.0f)) return false;
    p = {ray_x_[static_cast<std::size_t>(u)] * d, ry * d, d};
    return true;
  }

  const Image& depth_;
  Eigen::Isometry3f T_world_camera_;
  Eigen::Matrix3f rotation_;
  std::vector<float> ray_x_, ray_y_;  // (u - cx) / fx per column, (v - cy) / fy per row
};

bool has_matching_color(const DepthFrame& frame, const Image& depth_m) {
  return !frame.color.empty() && frame.color.same_size(depth_m) &&
         frame.color.format() == PixelFormat::RGB8;
}

Rgb8 color_at(const DepthFrame& frame, int u, int v) { return frame.color.at<Rgb8>(v, u); }

void set_sensor_origin(const DepthFrame& frame, PointCloud& cloud) {
  cloud.sensor_origin = frame.T_world_camera.translation();
  cloud.has_sensor_origin = true;
}

}  // namespace

PointCloud back_project(const DepthFrame& frame, const Image& depth_m) {
  const int w = depth_m.cols(), h = depth_m.rows();
  const std::size_t n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  const Eigen::Vector3f kNaN = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  PointCloud cloud;
  cloud.width = static_cast<std::uint32_t>(w);
  cloud.height = static_cast<std::uint32_t>(h);
  cloud.positions.resize(n);
  cloud.normals.resize(n);
  const bool color = has_matching_color(frame, depth_m);
  if (color) cloud.colors.resize(n);
  const PixelSurface surface(frame, depth_m);
  tbb::parallel_for(0, h, [&](int v) {
    for (int u = 0; u < w; ++u) {
      const std::size_t i =
          static_cast<std::size_t>(v) * static_cast<std::size_t>(w) + static_cast<std::size_t>(u);
      if (!surface.at(u, v, cloud.positions[i], cloud.normals[i])) {
        cloud.positions[i] = kNaN;
        cloud.normals[i] = kNaN;
      } else if (color) {
        cloud.colors[i] = color_at(frame, u, v);
      }
    }
  });
  set_sensor_origin(frame, cloud);
  return cloud;
}

PointCloud back_project_valid(const DepthFrame& frame, const Image& depth_m) {
  const int w = depth_m.cols(), h = depth_m.rows();
  const bool color = has_matching_color(frame, depth_m);
  const PixelSurface surface(frame, depth_m);
  // Pass 1 counts each row's valid pixels, pass 2 writes them at the row's offset (recomputing
  // a pixel is cheaper than buffering it).
  std::vector<std::size_t> offsets(static_cast<std::size_t>(h));
  tbb::parallel_for(0, h, [&](int v) {
    std::size_t count = 0;
    Eigen::Vector3f p, n;
    for (int u = 0; u < w; ++u) count += surface.at(u, v, p, n) ? 1 : 0;
    offsets[static_cast<std::size_t>(v)] = count;
  });
  const std::size_t total = exclusive_scan_in_place(offsets);
  PointCloud cloud;
  cloud.positions.resize(total);
  cloud.normals.resize(total);
  if (color) cloud.colors.resize(total);
  tbb::parallel_for(0, h, [&](int v) {
    std::size_t i = offsets[static_cast<std::size_t>(v)];
    Eigen::Vector3f p, n;
    for (int u = 0; u < w; ++u) {
      if (!surface.at(u, v, p, n)) continue;
      cloud.positions[i] = p;
      cloud.normals[i] = n;
      if (color) cloud.colors[i] = color_at(frame, u, v);
      ++i;
    }
  });
  set_sensor_origin(frame, cloud);
  return cloud;
}

}  // namespace meshflow
