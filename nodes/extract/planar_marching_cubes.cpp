#include "nodes/extract/planar_marching_cubes.h"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <utility>

#include "runtime/angles.h"
#include "runtime/parallel.h"

namespace meshflow {
namespace {

// Outward in-plane direction and normal sums of every vertex on a border edge.
struct BorderVertices {
  std::vector<std::uint32_t> ids;
  std::vector<Eigen::Vector3f> outward, normal;
};

BorderVertices border_vertices(const TriangleMesh& mesh) {
  std::vector<Eigen::Vector3f> outward(mesh.vertices.size(), Eigen::Vector3f::Zero());
  std::vector<Eigen::Vector3f> normal(mesh.vertices.size(), Eigen::Vector3f::Zero());
  std::vector<std::uint8_t> on_border(mesh.vertices.size(), 0);
  for (const BorderEdge& e : border_edges(mesh)) {
    const Eigen::Vector3f n = face_normal(mesh, mesh.triangles[e.triangle]);
    // Counter-clockwise seen from n: the triangle lies left of a -> b, outside to the right.
    const Eigen::Vector3f o = (mesh.vertices[e.b] - mesh.vertices[e.a]).cross(n).normalized();
    for (std::uint32_t v : {e.a, e.b}) {
      outward[v] += o;
      normal[v] += n;
      on_border[v] = 1;
    }
  }
  BorderVertices out;
  for (std::uint32_t v = 0; v < mesh.vertices.size(); ++v) {
    if (!on_border[v]) continue;
    out.ids.push_back(v);
    out.outward.push_back(outward[v]);
    out.normal.push_back(normal[v]);
  }
  return out;
}

}  // namespace

void move_border_to_contour(TriangleMesh& mesh, const PointCloud& cloud, const SpatialIndex& index,
                            float voxel_size, const PlanarContourConfig& config) {
  const BorderVertices border = border_vertices(mesh);
  const float reach = config.search_voxels * voxel_size;
  const float strip = config.strip_voxels * voxel_size, gap = config.gap_voxels * voxel_size;
  std::vector<Eigen::Vector3f> moved(border.ids.size());
  tbb::parallel_for(std::size_t{0}, border.ids.size(), [&](std::size_t i) {
    const Eigen::Vector3f v = mesh.vertices[border.ids[i]];
    moved[i] = v;
    const Eigen::Vector3f n = border.normal[i].normalized();
    Eigen::Vector3f o = border.outward[i] - border.outward[i].dot(n) * n;
    if (!(o.norm() > 1e-6f) || !n.allFinite()) return;
    o.normalize();
    const Eigen::Vector3f along = n.cross(o);
    std::vector<float> offsets;  // of the strip's points across the border
    for (std::uint32_t p : index.radius_search(v, reach)) {
      const Eigen::Vector3f d = cloud.positions[p] - v;
      if (std::abs(d.dot(along)) <= strip && std::abs(d.dot(n)) <= reach)
        offsets.push_back(d.dot(o));
    }
    if (offsets.empty()) return;
    std::sort(offsets.begin(), offsets.end());
    // From the inner side outwards, the run ends at the first gap: that is the contour.
    std::size_t k = 0;
    while (k + 1 < offsets.size() && offsets[k + 1] - offsets[k] <= gap) ++k;
    moved[i] = v + o * offsets[k];
  });
  for (std::size_t i = 0; i < border.ids.size(); ++i) mesh.vertices[border.ids[i]] = moved[i];
  // A border triangle whose three vertices now lie on one straight contour has no area left:
  // drop it (its inner edge becomes the border, on the contour too).
  const std::vector<std::uint32_t> kept = parallel_select_indices(
      mesh.triangles.size(),
      [&](std::size_t t) { return !face_normal(mesh, mesh.triangles[t]).isZero(); });
  if (kept.size() == mesh.triangles.size()) return;
  std::vector<Triangle> triangles(kept.size());
  tbb::parallel_for(std::size_t{0}, kept.size(),
                    [&](std::size_t k) { triangles[k] = mesh.triangles[kept[k]]; });
  mesh.triangles = std::move(triangles);
}

std::vector<std::uint8_t> data_feature_vertices(const TriangleMesh& mesh, const PointCloud& cloud,
                                                const SpatialIndex& index, float voxel_size,
                                                float angle_deg, float reach_voxels) {
  std::vector<std::uint8_t> flags(mesh.vertices.size(), 0);
  if (cloud.normals.size() != cloud.positions.size() || cloud.positions.empty()) return flags;
  const auto cos_limit = static_cast<float>(std::cos(radians(static_cast<double>(angle_deg))));
  const float reach = reach_voxels * voxel_size;
  tbb::parallel_for(std::size_t{0}, mesh.vertices.size(), [&](std::size_t v) {
    const std::vector<std::uint32_t> near = index.radius_search(mesh.vertices[v], reach);
    if (near.empty()) return;
    const Eigen::Vector3f& reference = cloud.normals[near.front()];  // the nearest point's
    for (std::uint32_t p : near)
      if (reference.dot(cloud.normals[p]) < cos_limit) {
        flags[v] = 1;
        return;
      }
  });
  return flags;
}

TriangleMesh planar_marching_cubes(const SparseGrid& grid, const DistanceField& field,
                                   const PointCloud& cloud, const SpatialIndex& index,
                                   const ExtractConfig& config,
                                   const PlanarContourConfig& contour) {
  ExtractConfig plain = config;
  plain.vertex_normals = false;
  TriangleMesh mesh = marching_cubes(grid, field, plain);
  move_border_to_contour(mesh, cloud, index, grid.voxel_size, contour);
  if (config.vertex_normals) compute_vertex_normals(mesh);
  return mesh;
}

}  // namespace meshflow
