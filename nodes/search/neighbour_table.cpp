#include "nodes/search/neighbour_table.h"

#include <tbb/parallel_for.h>

namespace meshflow {

NeighbourTable build_neighbour_table(const std::vector<Eigen::Vector3f>& positions,
                                     const SpatialIndex& index, std::size_t k) {
  NeighbourTable table;
  table.k = k;
  table.indices.resize(positions.size() * k);
  table.counts.resize(positions.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, positions.size(), 512),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      std::vector<float> d2(k);
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        table.counts[i] = static_cast<std::uint32_t>(
                            index.knn(positions[i], k, table.indices.data() + i * k, d2.data()));
                      }
                    });
  return table;
}

}  // namespace meshflow
