#include "nodes/fusion/tsdf_sampling.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

namespace meshflow {
namespace {

// The weight of voxel (i, j, k), 0 when its block was never allocated or is out of range.
float voxel_weight(const TsdfMap& map, const Eigen::Vector3i& voxel) {
  const Eigen::Vector3i block = tsdf_block_of_voxel(voxel);
  if (!tsdf_block_in_range(block)) return 0.0f;
  const TsdfBlock* found = map.find(block);
  if (found == nullptr) return 0.0f;
  const Eigen::Vector3i local = voxel - block * kTsdfBlockSide;
  return found
      ->voxels[static_cast<std::size_t>(local.x() +
                                        kTsdfBlockSide * (local.y() + kTsdfBlockSide * local.z()))]
      .weight;
}

}  // namespace

std::vector<float> tsdf_weights_at(const TsdfMap& map, const std::vector<Eigen::Vector3f>& points) {
  std::vector<float> weights(points.size(), 0.0f);
  const double voxel = static_cast<double>(map.config().voxel_size);
  const double limit = static_cast<double>(kMaxTsdfBlockIndex) * kTsdfBlockSide;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 4096),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        const Eigen::Vector3d g = points[i].cast<double>() / voxel;
                        if (!g.allFinite() || (g.array().abs() > limit).any()) continue;
                        const Eigen::Vector3d low = g.array().floor();
                        const Eigen::Vector3d t = g - low;
                        const Eigen::Vector3i base = low.cast<int>();
                        double sum = 0.0;
                        for (int corner = 0; corner < 8; ++corner) {
                          const Eigen::Vector3i d(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
                          double w = 1.0;
                          for (int a = 0; a < 3; ++a) w *= d[a] != 0 ? t[a] : 1.0 - t[a];
                          if (w > 0.0) sum += w * static_cast<double>(voxel_weight(map, base + d));
                        }
                        weights[i] = static_cast<float>(sum);
                      }
                    });
  return weights;
}

}  // namespace meshflow
