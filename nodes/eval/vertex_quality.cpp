#include "nodes/eval/vertex_quality.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "nodes/search/spatial_index.h"
#include "runtime/error.h"

namespace meshflow {

namespace {

std::vector<Eigen::Vector3f> finite_only(const std::vector<Eigen::Vector3f>& points) {
  std::vector<Eigen::Vector3f> finite;
  finite.reserve(points.size());
  for (const Eigen::Vector3f& p : points)
    if (p.allFinite()) finite.push_back(p);
  return finite;
}

// vertex_support() with the radius count only when radius > 0.
VertexSupport support(const std::vector<Eigen::Vector3f>& queries,
                      const std::vector<Eigen::Vector3f>& points, float radius) {
  VertexSupport out;
  out.distances.assign(queries.size(), std::numeric_limits<float>::infinity());
  if (radius > 0.0f) out.observations.assign(queries.size(), 0.0f);
  const std::vector<Eigen::Vector3f> finite = finite_only(points);
  if (finite.empty()) return out;
  const KdTreeIndex index(finite);
  tbb::parallel_for(std::size_t{0}, queries.size(), [&](std::size_t i) {
    std::uint32_t nearest = 0;
    float squared = 0.0f;
    if (index.knn(queries[i], 1, &nearest, &squared) == 1) out.distances[i] = std::sqrt(squared);
    if (radius > 0.0f && queries[i].allFinite())
      out.observations[i] = static_cast<float>(index.radius_search(queries[i], radius).size());
  });
  return out;
}

}  // namespace

std::vector<float> nearest_point_distances(const std::vector<Eigen::Vector3f>& queries,
                                           const std::vector<Eigen::Vector3f>& points) {
  return support(queries, points, 0.0f).distances;
}

ObservationStats observation_stats(std::vector<float> counts) {
  ObservationStats s;
  s.vertices = counts.size();
  if (counts.empty()) return s;
  double sum = 0.0;
  for (float c : counts) sum += static_cast<double>(c);
  s.mean = sum / static_cast<double>(counts.size());
  s.min = *std::min_element(counts.begin(), counts.end());
  const auto at = [&counts](double share) {
    const auto k = static_cast<std::ptrdiff_t>(share * static_cast<double>(counts.size() - 1));
    std::nth_element(counts.begin(), counts.begin() + k, counts.end());
    return counts[static_cast<std::size_t>(k)];
  };
  s.median = at(0.5);
  s.p5 = at(0.05);
  return s;
}

VertexSupport vertex_support(const std::vector<Eigen::Vector3f>& queries,
                             const std::vector<Eigen::Vector3f>& points, float radius) {
  if (!(radius > 0.0f) || !std::isfinite(radius))
    throw Error("vertex support", std::to_string(radius), "expected a positive radius in metres");
  return support(queries, points, radius);
}

}  // namespace meshflow
