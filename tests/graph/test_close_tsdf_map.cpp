#include "graph/close_tsdf_map.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "nodes/extract/marching_cubes.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {
namespace {

// A TSDF map of a sphere (radius 6 voxels, in the middle of 3 x 3 x 3 blocks) observed only on
// its upper half, red where x is below the centre and blue above it.
TsdfMap half_seen_red_blue_sphere(float voxel, Eigen::Vector3f& centre, float& radius) {
  TsdfConfig config;
  config.voxel_size = voxel;
  TsdfMap map(config);
  centre = Eigen::Vector3f::Constant(12.0f * voxel);
  radius = 6.0f * voxel;
  const float truncation = config.truncation_voxels * voxel;
  for (int bz = 0; bz < 3; ++bz)
    for (int by = 0; by < 3; ++by)
      for (int bx = 0; bx < 3; ++bx) {
        std::array<TsdfVoxel, kTsdfBlockVoxels> voxels{};
        for (int v = 0; v < kTsdfBlockVoxels; ++v) {
          const Eigen::Vector3i at =
              Eigen::Vector3i(bx, by, bz) * kTsdfBlockSide +
              Eigen::Vector3i(v % kTsdfBlockSide, (v / kTsdfBlockSide) % kTsdfBlockSide,
                              v / (kTsdfBlockSide * kTsdfBlockSide));
          const Eigen::Vector3f p = at.cast<float>() * voxel;
          const float d = (p - centre).norm() - radius;
          if (p.z() < centre.z() || std::abs(d) > truncation) continue;  // unseen
          TsdfVoxel& out = voxels[static_cast<std::size_t>(v)];
          out.distance = d;
          out.weight = 1.0f;
          out.color = p.x() < centre.x() ? Rgb8{255, 0, 0} : Rgb8{0, 0, 255};
        }
        map.insert_block(Eigen::Vector3i(bx, by, bz), voxels);
      }
  return map;
}

// The closed surface's vertices take the nearest surface voxels' colours, the filled lower
// half included (the open mesher blends the map's colours; the closed grid has none).
TEST(CloseTsdfMap, ClosedMeshTakesTheNearestObservedColours) {
  const float voxel = 0.05f;
  Eigen::Vector3f centre;
  float radius = 0.0f;
  const TsdfMap map = half_seen_red_blue_sphere(voxel, centre, radius);
  const ClosedDistance closed = close_tsdf_map(map, 0.0f, CloseConfig{});
  const TriangleMesh mesh = marching_cubes(closed.grid, closed.distance);
  ASSERT_TRUE(edge_statistics(mesh).closed());
  const std::vector<Rgb8> colors = tsdf_map_vertex_colors(map, 0.0f, mesh.vertices);
  ASSERT_EQ(colors.size(), mesh.vertices.size());
  std::size_t checked = 0, filled = 0;
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    const Eigen::Vector3f d = mesh.vertices[v] - centre;
    // Clearly on one side: the nearest surface voxels (within a voxel or two where seen, on the
    // rim's nearest arc below) all have that side's colour.
    if (std::abs(d.x()) < 3.0f * voxel || std::abs(d.x()) < std::abs(d.y())) continue;
    const Rgb8 expected = d.x() < 0.0f ? Rgb8{255, 0, 0} : Rgb8{0, 0, 255};
    EXPECT_EQ(colors[v], expected) << mesh.vertices[v].transpose();
    ++checked;
    filled += d.z() < -2.0f * voxel ? 1 : 0;
  }
  EXPECT_GT(checked, 50u);
  EXPECT_GT(filled, 10u) << "vertices of the filled lower half checked";
  EXPECT_TRUE(tsdf_map_vertex_colors(TsdfMap(map.config()), 0.0f, mesh.vertices).empty())
      << "no surface voxel, no colours";
}

}  // namespace
}  // namespace meshflow
