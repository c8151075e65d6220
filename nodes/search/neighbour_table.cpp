#include "nodes/search/neighbour_table.h"

namespace meshflow {

NeighbourTable build_neighbour_table(const std::vector<Eigen::Vector3f>& positions,
                                     const SpatialIndex& index, std::size_t k) {
  NeighbourTable table;
  table.k = k;
  table.indices.resize(positions.size() * k);  // first written (faulted in) by the threads
  table.counts.resize(positions.size());
  index.knn_rows(positions, k, table.indices.data(), table.counts.data());
  return table;
}

}  // namespace meshflow
