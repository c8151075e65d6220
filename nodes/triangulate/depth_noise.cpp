#include "nodes/triangulate/depth_noise.h"

#include <cmath>

#include "nodes/depth/depth_noise.h"

namespace meshflow {

float estimate_noise_per_depth2(const PointGrid& grid) {
  if (grid.width < 3 || grid.height < 1) return 0.0f;
  return residual_percentile(grid.height, [&](int v, ResidualHistogram& h) {
    const Eigen::Vector3f* row = &grid.points[grid.index(0, v)];
    for (int u = 1; u + 1 < grid.width; u += kNoiseColumnStep) {
      const Eigen::Vector3f& p = row[u];
      const Eigen::Vector3f& l = row[u - 1];
      const Eigen::Vector3f& r = row[u + 1];
      if (std::isnan(p.x()) || std::isnan(l.x()) || std::isnan(r.x())) continue;
      const float depth2 = (p - grid.eye).squaredNorm();
      if (!(depth2 > 0.0f)) continue;
      h.add((p - (l + r) * 0.5f).norm() / depth2);
    }
  });
}

}  // namespace meshflow
