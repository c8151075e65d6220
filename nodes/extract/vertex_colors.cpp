#include "nodes/extract/vertex_colors.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cassert>
#include <cmath>

namespace meshflow {

std::vector<Rgb8> vertex_colors(const std::vector<Eigen::Vector3f>& vertices,
                                const PointCloud& cloud, const SpatialIndex& index, int k) {
  assert(cloud.colors.size() == cloud.positions.size());
  const std::size_t want = static_cast<std::size_t>(std::clamp(k, 1, 64));
  std::vector<Rgb8> colors(vertices.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertices.size(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      std::uint32_t idx[64];
                      float d2[64];
                      for (std::size_t v = r.begin(); v != r.end(); ++v) {
                        const std::size_t found = index.knn(vertices[v], want, idx, d2);
                        if (found == 0) continue;
                        if (!(d2[0] > 0.0f)) {  // on a point
                          colors[v] = cloud.colors[idx[0]];
                          continue;
                        }
                        Eigen::Vector3f sum = Eigen::Vector3f::Zero();
                        float weights = 0.0f;
                        for (std::size_t j = 0; j < found; ++j) {
                          const float w = 1.0f / std::sqrt(d2[j]);
                          const Rgb8& c = cloud.colors[idx[j]];
                          sum += w * Eigen::Vector3f(c.r, c.g, c.b);
                          weights += w;
                        }
                        const Eigen::Vector3f rgb = sum / weights;
                        colors[v] = Rgb8{static_cast<std::uint8_t>(std::lround(rgb.x())),
                                         static_cast<std::uint8_t>(std::lround(rgb.y())),
                                         static_cast<std::uint8_t>(std::lround(rgb.z()))};
                      }
                    });
  return colors;
}

}  // namespace meshflow
