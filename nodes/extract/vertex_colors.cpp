#include "nodes/extract/vertex_colors.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cassert>
#include <cmath>

namespace meshflow {

std::vector<Rgb8> vertex_colors(const std::vector<Eigen::Vector3f>& vertices,
                                const PointCloud& cloud, const SpatialIndex& index, int k) {
  assert(cloud.colors.size() == cloud.positions.size());
  const std::size_t want = static_cast<std::size_t>(std::clamp(k, 1, 64));
  std::vector<Rgb8> colors(vertices.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertices.size(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      std::uint32_t idx[64];
                      float d2[64];
                      for (std::size_t v = r.begin(); v != r.end(); ++v) {
                        const std::size_t found = index.knn(vertices[v], want, idx, d2);
                        if (found == 0) continue;
                        if (!(d2[0] > 0.0f)) {  // on a point
                          colors[v] = cloud.colors[idx[0]];
                          continue;
                        }
                        Eigen::Vector3f sum = Eigen::Vector3f::Zero();
                        float weights = 0.0f;
                        for (std::size_t j = 0; j < found; ++j) {
                          const float w = 1.0f / std::sqrt(d2[j]);
                          const Rgb8& c = cloud.colors[idx[j]];
                          sum += w * Eigen::Vector3f(c.r, c.g, c.b);
                          weights += w;
                        }
                        const Eigen::Vector3f rgb = sum / weights;
                        colors[v] = Rgb8{static_cast<std::uint8_t>(std::lround(rgb.x())),
                                         static_cast<std::uint8_t>(std::lround(rgb.y())),
                                         static_cast<std::uint8_t>(std::lround(rgb.z()))};
                      }
                    });
  return colors;
}

namespace {

// The colour at (u, v) (pixels, inside the image), bilinear between the 4 pixels around it.
Rgb8 bilinear_rgb(const Image& image, float u, float v) {
  const int u0 = std::min(static_cast<int>(u), std::max(image.cols() - 2, 0));
  const int v0 = std::min(static_cast<int>(v), std::max(image.rows() - 2, 0));
  const int u1 = std::min(u0 + 1, image.cols() - 1), v1 = std::min(v0 + 1, image.rows() - 1);
  const float a = u - static_cast<float>(u0), b = v - static_cast<float>(v0);
  const Rgb8& c00 = image.at<Rgb8>(v0, u0);
  const Rgb8& c10 = image.at<Rgb8>(v0, u1);
  const Rgb8& c01 = image.at<Rgb8>(v1, u0);
  const Rgb8& c11 = image.at<Rgb8>(v1, u1);
  const auto mix = [&](std::uint8_t x00, std::uint8_t x10, std::uint8_t x01, std::uint8_t x11) {
    const float value =
        (1 - a) * (1 - b) * x00 + a * (1 - b) * x10 + (1 - a) * b * x01 + a * b * x11;
    return static_cast<std::uint8_t>(std::lround(std::clamp(value, 0.0f, 255.0f)));
  };
  return Rgb8{mix(c00.r, c10.r, c01.r, c11.r), mix(c00.g, c10.g, c01.g, c11.g),
              mix(c00.b, c10.b, c01.b, c11.b)};
}

}  // namespace

std::vector<Rgb8> vertex_colors_from_image(const std::vector<Eigen::Vector3f>& vertices,
                                           const DepthFrame& frame) {
  const Image& image = frame.color;
  const PinholeIntrinsics& k = frame.intrinsics;
  if (image.empty() || image.format() != PixelFormat::RGB8 || image.cols() != k.width ||
      image.rows() != k.height)
    return {};
  const Eigen::Isometry3f camera_from_world = frame.T_world_camera.inverse();
  const float max_u = static_cast<float>(image.cols() - 1);
  const float max_v = static_cast<float>(image.rows() - 1);
  std::vector<Rgb8> colors(vertices.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertices.size(), 4096),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        const Eigen::Vector3f p = camera_from_world * vertices[i];
                        float u = k.cx, v = k.cy;  // behind the camera: the centre
                        if (p.z() > 1e-6f) {
                          u = k.fx * p.x() / p.z() + k.cx;
                          v = k.fy * p.y() / p.z() + k.cy;
                        }
                        colors[i] = bilinear_rgb(image, std::clamp(u, 0.0f, max_u),
                                                 std::clamp(v, 0.0f, max_v));
                      }
                    });
  return colors;
}

}  // namespace meshflow
