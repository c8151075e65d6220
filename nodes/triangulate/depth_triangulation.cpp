#include "nodes/triangulate/depth_triangulation.h"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "runtime/error.h"
#include "runtime/parallel.h"

namespace meshflow {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// A width x height grid of world points (NaN = invalid) seen from `eye`.
struct PointGrid {
  int width = 0, height = 0;
  std::vector<Eigen::Vector3f> points;
  Eigen::Vector3f eye = Eigen::Vector3f::Zero();
  bool valid(std::size_t i) const { return !std::isnan(points[i].x()); }
};

// The kept triangles of one quad, as corners 0 = (u, v), 1 = (u + 1, v), 2 = (u, v + 1),
// 3 = (u + 1, v + 1); counter-clockwise seen from the camera (x right, y down, z forward).
struct QuadTriangles {
  std::uint8_t count = 0;
  std::array<std::array<std::uint8_t, 3>, 2> tri{};
};

struct RowCounts {
  std::size_t quads = 0, rejected_view = 0, rejected_shape = 0;
};

// Splits and filters the quads of row v.
void triangulate_row(const PointGrid& g, int v, const DepthTriangulationConfig& config,
                     QuadTriangles* quads, RowCounts& counts) {
  const float min_cos_view = std::cos(config.max_view_angle_deg * 3.14159265f / 180.0f);
  for (int u = 0; u + 1 < g.width; ++u) {
    const std::size_t i0 = static_cast<std::size_t>(v) * static_cast<std::size_t>(g.width) +
                           static_cast<std::size_t>(u);
    const std::array<std::size_t, 4> id = {i0, i0 + 1, i0 + static_cast<std::size_t>(g.width),
                                           i0 + static_cast<std::size_t>(g.width) + 1};
    int valid_mask = 0;
    for (int c = 0; c < 4; ++c) valid_mask |= g.valid(id[static_cast<std::size_t>(c)]) << c;
    std::array<std::array<std::uint8_t, 3>, 2> candidates{};
    int n = 0;
    switch (valid_mask) {
      case 15: {  // along the shorter diagonal
        const float ad = (g.points[id[0]] - g.points[id[3]]).squaredNorm();
        const float bc = (g.points[id[1]] - g.points[id[2]]).squaredNorm();
        if (ad <= bc) {
          candidates = {{{0, 2, 3}, {0, 3, 1}}};
        } else {
          candidates = {{{0, 2, 1}, {1, 2, 3}}};
        }
        n = 2;
        break;
      }
      case 7:
        candidates[0] = {0, 2, 1};
        n = 1;
        break;  // no corner 3
      case 14:
        candidates[0] = {1, 2, 3};
        n = 1;
        break;  // no corner 0
      case 13:
        candidates[0] = {0, 2, 3};
        n = 1;
        break;  // no corner 1
      case 11:
        candidates[0] = {0, 3, 1};
        n = 1;
        break;  // no corner 2
      default:
        break;
    }
    QuadTriangles& out = quads[u];
    out.count = 0;
    if (n == 0) continue;
    ++counts.quads;
    for (int k = 0; k < n; ++k) {
      const auto& t = candidates[static_cast<std::size_t>(k)];
      const Eigen::Vector3f& p0 = g.points[id[t[0]]];
      const Eigen::Vector3f& p1 = g.points[id[t[1]]];
      const Eigen::Vector3f& p2 = g.points[id[t[2]]];
      const Eigen::Vector3f normal = (p1 - p0).cross(p2 - p0);
      const Eigen::Vector3f ray = (p0 + p1 + p2) / 3.0f - g.eye;
      const float area2 = normal.norm();
      if (!(std::abs(normal.dot(ray)) >= min_cos_view * area2 * ray.norm())) {
        ++counts.rejected_view;
        continue;
      }
      const float e0 = (p1 - p0).squaredNorm(), e1 = (p2 - p1).squaredNorm(),
                  e2 = (p0 - p2).squaredNorm();
      const float longest = std::max({e0, e1, e2}), shortest = std::min({e0, e1, e2});
      if (!(longest <= config.max_edge_ratio * config.max_edge_ratio * shortest)) {
        ++counts.rejected_shape;
        continue;
      }
      out.tri[out.count++] = t;
    }
  }
}

TriangleMesh triangulate_grid(const PointGrid& g, const DepthTriangulationConfig& config,
                              TriangulationCounts& counts) {
  TriangleMesh mesh;
  if (g.width < 2 || g.height < 2) return mesh;
  const std::size_t w = static_cast<std::size_t>(g.width), h = static_cast<std::size_t>(g.height);
  const std::size_t qw = w - 1, qh = h - 1;
  std::vector<QuadTriangles> quads(qw * qh);
  std::vector<RowCounts> row_counts(qh);
  tbb::parallel_for(std::size_t{0}, qh, [&](std::size_t v) {
    triangulate_row(g, static_cast<int>(v), config, quads.data() + v * qw, row_counts[v]);
  });
  // A pixel is a vertex when a kept triangle of one of its (up to) four quads uses it.
  auto corner_pixel = [&](std::size_t qu, std::size_t qv, std::uint8_t c) {
    return (qv + (c >> 1)) * w + qu + (c & 1);
  };
  std::vector<std::uint32_t> vertex_of(w * h, UINT32_MAX);
  std::vector<std::uint32_t> row_vertices(h, 0);
  tbb::parallel_for(std::size_t{0}, h, [&](std::size_t v) {
    std::uint32_t used = 0;
    for (std::size_t u = 0; u < w; ++u) {
      bool is_used = false;
      for (std::size_t dv = 0; dv < 2 && !is_used; ++dv) {
        if (v < dv || v - dv >= qh) continue;
        const std::size_t qv = v - dv;
        for (std::size_t du = 0; du < 2 && !is_used; ++du) {
          if (u < du || u - du >= qw) continue;
          const QuadTriangles& q = quads[qv * qw + u - du];
          const std::uint8_t corner = static_cast<std::uint8_t>(du | (dv << 1));
          for (std::uint8_t k = 0; k < q.count; ++k)
            for (std::uint8_t c : q.tri[k]) is_used = is_used || c == corner;
        }
      }
      if (is_used) vertex_of[v * w + u] = used++;  // row-local for now
    }
    row_vertices[v] = used;
  });
  mesh.vertices.resize(exclusive_scan_in_place(row_vertices));
  tbb::parallel_for(std::size_t{0}, h, [&](std::size_t v) {
    for (std::size_t u = 0; u < w; ++u) {
      std::uint32_t& id = vertex_of[v * w + u];
      if (id == UINT32_MAX) continue;
      id += row_vertices[v];
      mesh.vertices[id] = g.points[v * w + u];
    }
  });
  std::vector<std::uint32_t> row_triangles(qh, 0);
  tbb::parallel_for(std::size_t{0}, qh, [&](std::size_t v) {
    std::uint32_t n = 0;
    for (std::size_t u = 0; u < qw; ++u) n += quads[v * qw + u].count;
    row_triangles[v] = n;
  });
  mesh.triangles.resize(exclusive_scan_in_place(row_triangles));
  tbb::parallel_for(std::size_t{0}, qh, [&](std::size_t v) {
    std::uint32_t at = row_triangles[v];
    for (std::size_t u = 0; u < qw; ++u) {
      const QuadTriangles& q = quads[v * qw + u];
      for (std::uint8_t k = 0; k < q.count; ++k) {
        const auto& t = q.tri[k];
        mesh.triangles[at++] =
            Triangle{vertex_of[corner_pixel(u, v, t[0])], vertex_of[corner_pixel(u, v, t[1])],
                     vertex_of[corner_pixel(u, v, t[2])]};
      }
    }
  });
  for (const RowCounts& r : row_counts) {
    counts.quads += r.quads;
    counts.rejected_view += r.rejected_view;
    counts.rejected_shape += r.rejected_shape;
  }
  return mesh;
}

}  // namespace

TriangleMesh triangulate_depth(const DepthFrame& frame, const DepthTriangulationConfig& config,
                               TriangulationCounts* counts) {
  if (frame.depth.empty()) throw Error("depth frame", "depth", "empty image");
  if (frame.depth.cols != frame.intrinsics.width || frame.depth.rows != frame.intrinsics.height)
    throw Error("depth frame", "intrinsics",
                "image is " + std::to_string(frame.depth.cols) + "x" +
                    std::to_string(frame.depth.rows) + ", intrinsics say " +
                    std::to_string(frame.intrinsics.width) + "x" +
                    std::to_string(frame.intrinsics.height));
  TriangulationCounts c;
  const cv::Mat depth = filter_depth(frame, config.filter, &c.filter);
  PointGrid g;
  g.width = depth.cols;
  g.height = depth.rows;
  g.points.resize(static_cast<std::size_t>(g.width) * static_cast<std::size_t>(g.height));
  g.eye = frame.T_world_camera.translation();
  const PinholeIntrinsics& k = frame.intrinsics;
  tbb::parallel_for(0, g.height, [&](int v) {
    const float* row = depth.ptr<float>(v);
    for (int u = 0; u < g.width; ++u) {
      const float z = row[u];
      Eigen::Vector3f& p =
          g.points[static_cast<std::size_t>(v) * static_cast<std::size_t>(g.width) +
                   static_cast<std::size_t>(u)];
      if (!(z > 0.0f)) {
        p = Eigen::Vector3f::Constant(kNaN);
        continue;
      }
      const Eigen::Vector3f camera((static_cast<float>(u) - k.cx) / k.fx * z,
                                   (static_cast<float>(v) - k.cy) / k.fy * z, z);
      p = frame.T_world_camera * camera;
    }
  });
  TriangleMesh mesh = triangulate_grid(g, config, c);
  if (counts != nullptr) *counts = c;
  return mesh;
}

TriangleMesh triangulate_organized(const PointCloud& cloud, const DepthTriangulationConfig& config,
                                   TriangulationCounts* counts) {
  if (!cloud.is_organized())
    throw Error("point cloud", "width/height",
                "an organized cloud (width x height == points, height > 1) is needed; got " +
                    std::to_string(cloud.width) + "x" + std::to_string(cloud.height) + " for " +
                    std::to_string(cloud.size()) + " points");
  TriangulationCounts c;
  PointGrid g;
  g.width = static_cast<int>(cloud.width);
  g.height = static_cast<int>(cloud.height);
  g.eye = cloud.has_sensor_origin ? cloud.sensor_origin : Eigen::Vector3f::Zero();
  g.points = cloud.positions;
  // Range image for the limits and the occlusion edges (0 = invalid).
  cv::Mat range(g.height, g.width, CV_32F);
  c.filter.pixels = g.points.size();
  for (std::size_t i = 0; i < g.points.size(); ++i) {
    float& r =
        range.at<float>(static_cast<int>(i / cloud.width), static_cast<int>(i % cloud.width));
    if (!g.points[i].allFinite()) {
      ++c.filter.invalid;
      r = 0.0f;
      continue;
    }
    r = (g.points[i] - g.eye).norm();
    if (r < config.filter.min_depth || r > config.filter.max_depth) {
      ++c.filter.out_of_range;
      r = 0.0f;
    }
  }
  if (config.filter.edge_high > 0.0f) {
    const cv::Mat edges = occlusion_edges(
        range, config.filter.edge_high, std::min(config.filter.edge_low, config.filter.edge_high));
    c.filter.edges = static_cast<std::size_t>(cv::countNonZero(edges));
    range.setTo(0.0f, edges);
  }
  for (std::size_t i = 0; i < g.points.size(); ++i)
    if (range.at<float>(static_cast<int>(i / cloud.width), static_cast<int>(i % cloud.width)) <=
        0.0f)
      g.points[i] = Eigen::Vector3f::Constant(kNaN);
    else
      ++c.filter.valid;
  TriangleMesh mesh = triangulate_grid(g, config, c);
  if (counts != nullptr) *counts = c;
  return mesh;
}

}  // namespace meshflow
