#include "nodes/eval/vertex_quality.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>

#include "nodes/search/spatial_index.h"

namespace meshflow {

std::vector<float> nearest_point_distances(const std::vector<Eigen::Vector3f>& queries,
                                           const std::vector<Eigen::Vector3f>& points) {
  std::vector<Eigen::Vector3f> finite;
  finite.reserve(points.size());
  for (const Eigen::Vector3f& p : points)
    if (p.allFinite()) finite.push_back(p);
  std::vector<float> distances(queries.size(), std::numeric_limits<float>::infinity());
  if (finite.empty()) return distances;
  const KdTreeIndex index(finite);
  tbb::parallel_for(std::size_t{0}, queries.size(), [&](std::size_t i) {
    std::uint32_t nearest = 0;
    float squared = 0.0f;
    if (index.knn(queries[i], 1, &nearest, &squared) == 1) distances[i] = std::sqrt(squared);
  });
  return distances;
}

}  // namespace meshflow
