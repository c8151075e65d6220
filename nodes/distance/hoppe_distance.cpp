#include "nodes/distance/hoppe_distance.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <string>

#include "runtime/error.h"

namespace meshflow {

std::size_t DistanceField::valid_count() const {
  return static_cast<std::size_t>(std::count(valid.begin(), valid.end(), std::uint8_t{1}));
}

DistanceField hoppe_distance(const SparseGrid& grid, const PointCloud& cloud,
                             const SpatialIndex& index, const DistanceConfig& config) {
  if (cloud.normals.size() != cloud.positions.size())
    throw Error("distance", "normals",
                "the cloud needs one normal per point (estimate them first), has " +
                    std::to_string(cloud.normals.size()) + " for " +
                    std::to_string(cloud.positions.size()) + " points");
  const std::size_t n = grid.corners.size();
  const std::size_t kd = static_cast<std::size_t>(std::clamp(config.kd, 1, 64));
  const float max_d = config.max_distance_voxels * grid.voxel_size;
  const float max_d2 = max_d * max_d;
  DistanceField field;
  field.values.resize(n);
  field.valid.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      std::uint32_t idx[64];
                      float d2[64];
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        const Eigen::Vector3f q = grid.corner_position(i);
                        const std::size_t found = index.knn(q, kd, idx, d2);
                        if (found == 0 || d2[0] > max_d2) {
                          field.values[i] = 0.0f;
                          field.valid[i] = 0;
                          continue;
                        }
                        float sum = 0.0f;
                        for (std::size_t j = 0; j < found; ++j) {
                          sum += cloud.normals[idx[j]].dot(q - cloud.positions[idx[j]]);
                        }
                        field.values[i] = sum / static_cast<float>(found);
                        field.valid[i] = 1;
                      }
                    });
  return field;
}

}  // namespace meshflow
