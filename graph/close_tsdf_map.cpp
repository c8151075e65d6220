#include "graph/close_tsdf_map.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <cmath>
#include <utility>
#include <vector>

#include "nodes/extract/vertex_colors.h"
#include "nodes/search/spatial_index.h"
#include "runtime/point_cloud.h"
#include "runtime/voxel_key.h"

namespace meshflow {

ClosedDistance tsdf_map_distances(const TsdfMap& map, float min_weight) {
  const std::vector<std::uint32_t> order = map.blocks_in_key_order();
  std::vector<std::vector<std::pair<VoxelKey, float>>> per_block(order.size());
  tbb::parallel_for(std::size_t{0}, order.size(), [&](std::size_t b) {
    const TsdfBlock& block = map.block(order[b]);
    const Eigen::Vector3i base = block.coords * kTsdfBlockSide;
    for (int v = 0; v < kTsdfBlockVoxels; ++v) {
      const TsdfVoxel& voxel = block.voxels[static_cast<std::size_t>(v)];
      if (!(voxel.weight > min_weight)) continue;
      const Eigen::Vector3i at =
          base + Eigen::Vector3i(v % kTsdfBlockSide, (v / kTsdfBlockSide) % kTsdfBlockSide,
                                 v / (kTsdfBlockSide * kTsdfBlockSide));
      per_block[b].emplace_back(pack_key(at), voxel.distance);
    }
  });
  std::vector<std::pair<VoxelKey, float>> samples;
  for (const auto& block : per_block) samples.insert(samples.end(), block.begin(), block.end());
  tbb::parallel_sort(samples.begin(), samples.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
  ClosedDistance out;
  out.grid.voxel_size = map.config().voxel_size;
  out.grid.corners.resize(samples.size());
  out.distance.values.resize(samples.size());
  out.distance.valid.assign(samples.size(), 1);
  tbb::parallel_for(std::size_t{0}, samples.size(), [&](std::size_t i) {
    out.grid.corners[i] = samples[i].first;
    out.distance.values[i] = samples[i].second;
  });
  return out;
}

ClosedDistance close_tsdf_map(const TsdfMap& map, float min_weight, const CloseConfig& config,
                              CloseReport* report) {
  const ClosedDistance data = tsdf_map_distances(map, min_weight);
  return close_distance_field(data.grid, data.distance, PointCloud{}, config, report);
}

std::vector<Rgb8> tsdf_map_vertex_colors(const TsdfMap& map, float min_weight,
                                         const std::vector<Eigen::Vector3f>& vertices) {
  const float voxel_size = map.config().voxel_size;
  const std::vector<std::uint32_t> order = map.blocks_in_key_order();
  std::vector<PointCloud> per_block(order.size());
  tbb::parallel_for(std::size_t{0}, order.size(), [&](std::size_t b) {
    const TsdfBlock& block = map.block(order[b]);
    const Eigen::Vector3i base = block.coords * kTsdfBlockSide;
    for (int v = 0; v < kTsdfBlockVoxels; ++v) {
      const TsdfVoxel& voxel = block.voxels[static_cast<std::size_t>(v)];
      if (!(voxel.weight > min_weight) || !(std::abs(voxel.distance) < voxel_size)) continue;
      const Eigen::Vector3i at =
          base + Eigen::Vector3i(v % kTsdfBlockSide, (v / kTsdfBlockSide) % kTsdfBlockSide,
                                 v / (kTsdfBlockSide * kTsdfBlockSide));
      per_block[b].positions.push_back(at.cast<float>() * voxel_size);
      per_block[b].colors.push_back(voxel.color);
    }
  });
  PointCloud surface;
  for (const PointCloud& block : per_block) {
    surface.positions.insert(surface.positions.end(), block.positions.begin(),
                             block.positions.end());
    surface.colors.insert(surface.colors.end(), block.colors.begin(), block.colors.end());
  }
  if (surface.empty()) return {};
  const KdTreeIndex index(surface.positions);
  return vertex_colors(vertices, surface, index, 4);
}

}  // namespace meshflow
