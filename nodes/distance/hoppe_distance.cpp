#include "nodes/distance/hoppe_distance.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <string>

#include "runtime/error.h"

namespace meshflow {

namespace {

enum class Verdict : std::uint8_t { kValid, kTooFar, kDisagreeing, kExtrapolated };

// The distance at q from its `found` nearest points (closest first) and why it is invalid.
Verdict corner_distance(const Eigen::Vector3f& q, const std::uint32_t* idx, const float* d2,
                        std::size_t found, const PointCloud& cloud, float max_d2,
                        float disagreement, float extrapolation, float& value) {
  value = 0.0f;
  if (found == 0 || d2[0] > max_d2) return Verdict::kTooFar;
  float sum = 0.0f, lowest = 0.0f, highest = 0.0f;
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero(), mean_normal = Eigen::Vector3f::Zero();
  for (std::size_t j = 0; j < found; ++j) {
    const Eigen::Vector3f& p = cloud.positions[idx[j]];
    const Eigen::Vector3f& n = cloud.normals[idx[j]];
    const float d = n.dot(q - p);
    sum += d;
    lowest = std::min(lowest, d);
    highest = std::max(highest, d);
    centroid += p;
    mean_normal += n;
  }
  value = sum / static_cast<float>(found);
  if (disagreement > 0.0f && lowest < -disagreement && highest > disagreement)
    return Verdict::kDisagreeing;
  if (extrapolation > 0.0f && found >= 2) {
    centroid /= static_cast<float>(found);
    const float length = mean_normal.norm();
    if (length > 0.0f) {
      mean_normal /= length;
      Eigen::Vector3f foot = q - centroid;
      foot -= foot.dot(mean_normal) * mean_normal;  // q's foot, relative to the centroid
      const float reach = foot.norm();
      if (reach > extrapolation) {
        const Eigen::Vector3f direction = foot / reach;
        float extent = 0.0f;
        for (std::size_t j = 0; j < found; ++j)
          extent = std::max(extent, (cloud.positions[idx[j]] - centroid).dot(direction));
        if (reach > extent + extrapolation) return Verdict::kExtrapolated;
      }
    }
  }
  return Verdict::kValid;
}

}  // namespace

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
  const float disagreement = config.max_disagreement_voxels * grid.voxel_size;
  const float extrapolation = config.max_extrapolation_voxels * grid.voxel_size;
  std::vector<Verdict> verdict(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      std::uint32_t idx[64];
                      float d2[64];
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        const Eigen::Vector3f q = grid.corner_position(i);
                        const std::size_t found = index.knn(q, kd, idx, d2);
                        verdict[i] = corner_distance(q, idx, d2, found, cloud, max_d2, disagreement,
                                                     extrapolation, field.values[i]);
                        field.valid[i] = verdict[i] == Verdict::kValid ? 1 : 0;
                      }
                    });
  for (Verdict v : verdict) {
    field.disagreeing += v == Verdict::kDisagreeing ? 1 : 0;
    field.extrapolated += v == Verdict::kExtrapolated ? 1 : 0;
  }
  return field;
}

}  // namespace meshflow
