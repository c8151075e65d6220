#pragma once
// A densely sampled analytic solid taken through voxelize + Hoppe distance (exact normals), the
// input every extraction method is tested on.

#include <memory>
#include <string>
#include <vector>

#include "nodes/distance/hoppe_distance.h"
#include "nodes/normals/spatial_index.h"
#include "nodes/synthetic/shapes.h"
#include "nodes/synthetic/solids.h"
#include "nodes/voxelize/sparse_grid.h"

namespace meshflow::test {

struct SampledSolid {
  synthetic::Solid solid;
  std::unique_ptr<KdTreeIndex> index;
  SparseGrid grid;
  DistanceField field;
};

/// Samples `solid` (already sampled at voxel / 4 or finer), builds the grid at `voxel` and the
/// Hoppe distance (kd = 5).
inline SampledSolid sampled_solid(synthetic::Solid solid, float voxel) {
  SampledSolid s;
  s.solid = std::move(solid);
  s.index = std::make_unique<KdTreeIndex>(s.solid.samples.positions);
  s.grid = voxelize(s.solid.samples, VoxelizeConfig{voxel, 0.5f});
  s.field = hoppe_distance(s.grid, s.solid.samples, *s.index, DistanceConfig{});
  return s;
}

struct NamedSolid {
  std::string name;
  synthetic::Solid solid;
};

inline synthetic::Solid sphere_solid(const synthetic::Sphere& sphere, float spacing) {
  synthetic::Solid solid;
  solid.sdf = [sphere](const Eigen::Vector3f& p) {
    return (p - sphere.center).norm() - sphere.radius;
  };
  solid.samples = synthetic::sample_surface(sphere, spacing, 0.0f, 1);
  for (const auto& p : solid.samples.positions)
    solid.samples.normals.push_back((p - sphere.center).normalized());
  return solid;
}

// The analytic test shapes (cube, chamfered cube, union of two boxes, cylinder, sphere),
// sampled at a quarter voxel. The offsets keep faces off the grid
// planes (a face exactly on a lattice plane is a valid but degenerate-prone input).
inline std::vector<NamedSolid> test_solids(float voxel) {
  const float s = voxel / 4;
  const Eigen::Vector3f c(0.013f, -0.021f, 0.007f);
  return {
      {"cube", make_solid(synthetic::box_polytope(c, {0.4f, 0.4f, 0.4f}), s)},
      {"chamfered cube", make_solid(synthetic::chamfered_box(c, {0.4f, 0.4f, 0.4f}, 0.15f), s)},
      {"two boxes",
       make_union(make_solid(synthetic::box_polytope(c, {0.4f, 0.25f, 0.2f}), s),
                  make_solid(synthetic::box_polytope(c + Eigen::Vector3f(0.25f, 0.2f, 0.15f),
                                                     {0.2f, 0.2f, 0.2f}),
                             s))},
      {"cylinder", make_solid(synthetic::Cylinder{c, 0.35f, 0.3f}, s)},
      {"sphere", sphere_solid({c, 0.4f}, s)},
  };
}

}  // namespace meshflow::test
