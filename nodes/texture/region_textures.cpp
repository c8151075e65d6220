#include "nodes/texture/region_textures.h"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "nodes/search/spatial_index.h"
#include "runtime/error.h"

namespace meshflow {
namespace {

// The region's plane as an origin and two in-plane axes (u x v = normal).
struct PlaneFrame {
  Eigen::Vector3f origin, axis_u, axis_v;
  float u0 = 0, v0 = 0;  // lower-left corner of the texture, plane coordinates (metres)
  float texel = 0;
  int width = 1, height = 1;

  Eigen::Vector2f plane_coordinates(const Eigen::Vector3f& p) const {
    return {axis_u.dot(p - origin), axis_v.dot(p - origin)};
  }
};

PlaneFrame frame_of(const TriangleMesh& mesh, const PlanarRegion& region,
                    const TextureConfig& config) {
  PlaneFrame f;
  f.origin = region.normal * region.offset;
  f.axis_u = region.normal.unitOrthogonal();
  f.axis_v = region.normal.cross(f.axis_u);
  Eigen::Vector2f lo = Eigen::Vector2f::Constant(std::numeric_limits<float>::max());
  Eigen::Vector2f hi = -lo;
  for (std::uint32_t t : region.faces)
    for (std::uint32_t v : mesh.triangles[t]) {
      const Eigen::Vector2f q = f.plane_coordinates(mesh.vertices[v]);
      lo = lo.cwiseMin(q);
      hi = hi.cwiseMax(q);
    }
  const Eigen::Vector2f extent = (hi - lo).cwiseMax(1e-6f);
  f.texel = std::max(config.texel_size,
                     extent.maxCoeff() / static_cast<float>(std::max(1, config.max_texture_size)));
  f.width = std::max(1, static_cast<int>(std::ceil(extent.x() / f.texel)));
  f.height = std::max(1, static_cast<int>(std::ceil(extent.y() / f.texel)));
  f.u0 = lo.x();
  f.v0 = lo.y();
  return f;
}

}  // namespace

TexturedMesh texture_planar_regions(const TriangleMesh& mesh,
                                    const PlanarSegmentation& segmentation,
                                    const PointCloud& points, const TextureConfig& config) {
  if (!points.has_colors() || points.colors.size() != points.positions.size())
    throw Error("texture", "input points", "colours are needed to texture a mesh");
  if (points.positions.empty()) throw Error("texture", "input points", "no points");
  const KdTreeIndex index(points.positions);
  const float max_distance2 = config.max_distance * config.max_distance;
  auto nearest = [&](const Eigen::Vector3f& p, float* distance2) {
    std::uint32_t i = 0;
    float d2 = 0.0f;
    index.knn(p, 1, &i, &d2);
    if (distance2 != nullptr) *distance2 = d2;
    return points.colors[i];
  };

  TexturedMesh out;
  out.mesh = mesh;
  out.mesh.colors.resize(mesh.vertices.size());
  tbb::parallel_for(std::size_t{0}, mesh.vertices.size(), [&](std::size_t v) {
    out.mesh.colors[v] = nearest(mesh.vertices[v], nullptr);
  });
  out.texture_of_face.assign(mesh.triangles.size(), -1);
  out.uv.assign(mesh.triangles.size() * 3, Eigen::Vector2f::Zero());

  for (const PlanarRegion& region : segmentation.regions) {
    if (region.faces.size() < config.min_region_faces) continue;
    const PlaneFrame f = frame_of(mesh, region, config);
    RegionTexture texture;
    texture.faces = region.faces;
    texture.image = Image(f.height, f.width, PixelFormat::RGB8);
    tbb::parallel_for(0, f.height, [&](int row) {
      const float v = f.v0 + (static_cast<float>(f.height - 1 - row) + 0.5f) * f.texel;
      auto* pixel = texture.image.ptr<Rgb8>(row);
      for (int column = 0; column < f.width; ++column) {
        const float u = f.u0 + (static_cast<float>(column) + 0.5f) * f.texel;
        float d2 = 0.0f;
        const Rgb8 c = nearest(f.origin + u * f.axis_u + v * f.axis_v, &d2);
        pixel[column] = d2 <= max_distance2 ? c : Rgb8{128, 128, 128};
      }
    });
    const auto id = static_cast<std::int32_t>(out.textures.size());
    const Eigen::Vector2f scale(1.0f / (static_cast<float>(f.width) * f.texel),
                                1.0f / (static_cast<float>(f.height) * f.texel));
    for (std::uint32_t t : region.faces) {
      out.texture_of_face[t] = id;
      for (std::size_t k = 0; k < 3; ++k) {
        const Eigen::Vector2f q = f.plane_coordinates(mesh.vertices[mesh.triangles[t][k]]);
        out.uv[3 * t + k] = (q - Eigen::Vector2f(f.u0, f.v0)).cwiseProduct(scale);
      }
    }
    out.textures.push_back(std::move(texture));
  }
  return out;
}

}  // namespace meshflow
