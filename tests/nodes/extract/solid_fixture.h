#pragma once
// A densely sampled analytic solid taken through voxelize + Hoppe distance (exact normals), the
// input every extraction method is tested on.

#include <memory>

#include "nodes/distance/hoppe_distance.h"
#include "nodes/normals/spatial_index.h"
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

}  // namespace meshflow::test
