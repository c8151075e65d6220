#include "nodes/triangulate/pixel_grid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "runtime/error.h"
#include "runtime/parallel.h"
#include "runtime/simd.h"

namespace meshflow {
namespace {
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// One row of back-projection: point u = eye + z_u (x_u axis + ray), interleaved x, y, z into
// `out`; a depth <= 0 becomes NaN, which makes every coordinate NaN. Plain floats, without
// branches, so the loop vectorises (Eigen's 3-vectors would not); the operations and their
// order are those of the Eigen expression.
MESHFLOW_AVX2_CLONES void back_project_row(const float* depth, const float* x_of_column, int width,
                                           const float eye[3], const float axis[3],
                                           const float ray[3], float* out) {
  for (int u = 0; u < width; ++u) {
    const float z = depth[u] > 0.0f ? depth[u] : kNaN, x = x_of_column[u];
    for (int c = 0; c < 3; ++c) out[3 * u + c] = eye[c] + z * (axis[c] * x + ray[c]);
  }
}

}  // namespace

PointGrid grid_from_depth(const DepthFrame& frame, const DepthFilterConfig& filter,
                          DepthFilterCounts* counts) {
  const Image depth = filter_depth(frame, filter, counts);  // checks the frame
  PointGrid g;
  g.width = depth.cols();
  g.height = depth.rows();
  g.points.resize(static_cast<std::size_t>(g.width) * static_cast<std::size_t>(g.height));
  g.eye = frame.T_world_camera.translation();
  const PinholeIntrinsics& k = frame.intrinsics;
  // World point of pixel (u, v) at depth z: eye + z (R (x_u, y_v, 1)) with x_u = (u - cx) / fx
  // and y_v = (v - cy) / fy, so each row needs one ray per column, with no division.
  const Eigen::Matrix3f rotation = frame.T_world_camera.rotation();
  std::vector<float> x_of_column(static_cast<std::size_t>(g.width));
  for (int u = 0; u < g.width; ++u)
    x_of_column[static_cast<std::size_t>(u)] = (static_cast<float>(u) - k.cx) / k.fx;
  const float eye[3] = {g.eye.x(), g.eye.y(), g.eye.z()};
  const float axis[3] = {rotation(0, 0), rotation(1, 0), rotation(2, 0)};
  tbb::parallel_for(0, g.height, [&](int v) {
    const Eigen::Vector3f row_ray =
        rotation.col(1) * ((static_cast<float>(v) - k.cy) / k.fy) + rotation.col(2);
    const float ray[3] = {row_ray.x(), row_ray.y(), row_ray.z()};
    back_project_row(depth.ptr<float>(v), x_of_column.data(), g.width, eye, axis, ray,
                     g.points[g.index(0, v)].data());
  });
  return g;
}

PointGrid grid_from_organized(const PointCloud& cloud, const DepthFilterConfig& filter,
                              DepthFilterCounts* counts) {
  if (!cloud.is_organized())
    throw Error("point cloud", "width/height",
                "an organized cloud (width x height == points, height > 1) is needed; got " +
                    std::to_string(cloud.width) + "x" + std::to_string(cloud.height) + " for " +
                    std::to_string(cloud.size()) + " points");
  if (cloud.has_sensor_origin && !cloud.sensor_origin.allFinite())
    throw Error("point cloud", "sensor_origin",
                "is not finite (every range from it would be NaN, every pixel invalid)");
  DepthFilterCounts c;
  PointGrid g;
  g.width = static_cast<int>(cloud.width);
  g.height = static_cast<int>(cloud.height);
  g.eye = cloud.has_sensor_origin ? cloud.sensor_origin : Eigen::Vector3f::Zero();
  g.points = cloud.positions;
  if (cloud.colors.size() == cloud.positions.size()) g.colors = cloud.colors;
  if (cloud.normals.size() == cloud.positions.size()) g.normals = cloud.normals;
  // Range image for the limits and the occlusion edges (0 = invalid).
  Image range(g.height, g.width, PixelFormat::F32);
  c.pixels = g.points.size();
  for (int v = 0; v < g.height; ++v)
    for (int u = 0; u < g.width; ++u) {
      const Eigen::Vector3f& p = g.points[g.index(u, v)];
      float& r = range.at<float>(v, u);
      r = 0.0f;
      if (!p.allFinite()) {
        ++c.invalid;
        continue;
      }
      const float d = (p - g.eye).norm();
      if (d < filter.min_depth || d > filter.max_depth) {
        ++c.out_of_range;
        continue;
      }
      r = d;
    }
  if (filter.edge_high > 0.0f) {
    const Image edges =
        occlusion_edges(range, filter.edge_high, std::min(filter.edge_low, filter.edge_high));
    c.edges = count_nonzero(edges);
    for (int v = 0; v < g.height; ++v)
      for (int u = 0; u < g.width; ++u)
        if (edges.at<std::uint8_t>(v, u) != 0) range.at<float>(v, u) = 0.0f;
  }
  for (int v = 0; v < g.height; ++v)
    for (int u = 0; u < g.width; ++u) {
      if (range.at<float>(v, u) > 0.0f)
        ++c.valid;
      else
        g.points[g.index(u, v)] = Eigen::Vector3f::Constant(kNaN);
    }
  if (counts != nullptr) *counts = c;
  return g;
}

OcclusionTriangleTest::OcclusionTriangleTest(float max_view_angle_deg, float max_edge_ratio)
    : min_cos_view_squared_(std::pow(std::cos(max_view_angle_deg * 3.14159265f / 180.0f), 2.0f)),
      max_ratio_squared_(max_edge_ratio * max_edge_ratio) {}

namespace {

// A batch of triangles' corners, one array per coordinate (corner k, axis a at [3 k + a]).
constexpr std::size_t kBatch = 64;
using CornerLanes = float[9][kBatch];

// The verdicts of the first `n` triangles of `c` (a vectorised loop).
MESHFLOW_AVX2_CLONES void batch_verdicts(const CornerLanes& c, std::size_t n, const float eye[3],
                                         float min_cos_view_squared, float max_ratio_squared,
                                         std::uint8_t* verdicts) {
  for (std::size_t i = 0; i < n; ++i) {
    const float corners[9] = {c[0][i], c[1][i], c[2][i], c[3][i], c[4][i],
                              c[5][i], c[6][i], c[7][i], c[8][i]};
    verdicts[i] = static_cast<std::uint8_t>(
        OcclusionTriangleTest::verdict(corners, eye, min_cos_view_squared, max_ratio_squared));
  }
}

}  // namespace

void OcclusionTriangleTest::filter(const PointGrid& grid, std::vector<Triangle>& triangles,
                                   std::size_t first, OcclusionRejections* rejected) const {
  CornerLanes corners;
  std::uint8_t verdicts[kBatch];
  const float eye[3] = {grid.eye.x(), grid.eye.y(), grid.eye.z()};
  std::size_t kept = first, view = 0, shape = 0;
  for (std::size_t begin = first; begin < triangles.size(); begin += kBatch) {
    const std::size_t n = std::min(kBatch, triangles.size() - begin);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t k = 0; k < 3; ++k) {
        const Eigen::Vector3f& p = grid.points[triangles[begin + i][k]];
        corners[3 * k][i] = p.x();
        corners[3 * k + 1][i] = p.y();
        corners[3 * k + 2][i] = p.z();
      }
    batch_verdicts(corners, n, eye, min_cos_view_squared_, max_ratio_squared_, verdicts);
    for (std::size_t i = 0; i < n; ++i) {  // in place: kept <= begin + i
      triangles[kept] = triangles[begin + i];
      kept += verdicts[i] == kKeep;
      view += verdicts[i] == kViewAngle;
      shape += verdicts[i] == kShape;
    }
  }
  triangles.resize(kept);
  if (rejected != nullptr) {
    rejected->view += view;
    rejected->shape += shape;
  }
}

TriangleMesh mesh_from_grid_pixels(const PointGrid& grid, const std::vector<std::uint32_t>& pixels,
                                   std::vector<Triangle> triangles) {
  TriangleMesh mesh;
  const std::size_t n = pixels.size(), grid_pixels = grid.points.size();
  const bool colors = grid.colors.size() == grid_pixels,
             normals = grid.normals.size() == grid_pixels;
  mesh.vertices.resize(n);
  if (colors) mesh.colors.resize(n);
  if (normals) mesh.normals.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t i = range.begin(); i != range.end(); ++i) {
                        const std::uint32_t p = pixels[i];
                        mesh.vertices[i] = grid.points[p];
                        if (colors) mesh.colors[i] = grid.colors[p];
                        if (normals) mesh.normals[i] = grid.normals[p];
                      }
                    });
  mesh.triangles = std::move(triangles);
  return mesh;
}

TriangleMesh mesh_from_pixel_triangles(const PointGrid& grid,
                                       std::vector<Triangle> pixel_triangles) {
  const std::vector<std::uint32_t> pixels =
      renumber_used_vertices(pixel_triangles, grid.points.size());
  return mesh_from_grid_pixels(grid, pixels, std::move(pixel_triangles));
}

}  // namespace meshflow
