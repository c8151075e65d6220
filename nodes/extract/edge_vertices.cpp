#include "nodes/extract/edge_vertices.h"

#include <tbb/parallel_for.h>

#include <algorithm>

#include "runtime/parallel.h"

namespace meshflow {
EdgeVertexTable::EdgeVertexTable(std::size_t corners, std::size_t directions)
    : directions_(directions),
      size_(corners * directions),
      marked_(new std::uint8_t[corners * directions]),
      upper_(new std::uint32_t[corners * directions]) {  // uninitialised: read where marked
  const std::size_t blocks = (size_ + kParallelBlock - 1) / kParallelBlock;
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    const std::size_t begin = b * kParallelBlock, end = std::min(size_, begin + kParallelBlock);
    std::fill(marked_.get() + begin, marked_.get() + end, std::uint8_t{0});
  });
}

std::vector<Eigen::Vector3f> EdgeVertexTable::place_vertices(const SparseGrid& grid,
                                                             const DistanceField& field,
                                                             float iso) {
  const std::size_t blocks = (size_ + kParallelBlock - 1) / kParallelBlock;
  auto block_end = [&](std::size_t b) { return std::min(size_, (b + 1) * kParallelBlock); };
  std::vector<std::uint32_t> block_offsets(blocks);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    std::uint32_t count = 0;
    for (std::size_t k = b * kParallelBlock; k < block_end(b); ++k) count += marked_[k];
    block_offsets[b] = count;
  });
  std::vector<Eigen::Vector3f> vertices(exclusive_scan_in_place(block_offsets));
  // Each marked slot's vertex takes the place of its upper corner, read just before: the
  // table keeps one word per segment, not two (4 bytes per segment less at the peak).
  vertex_ = std::move(upper_);
  segment_of_vertex_.resize(vertices.size());
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    std::uint32_t v = block_offsets[b];
    for (std::size_t k = b * kParallelBlock; k < block_end(b); ++k) {
      if (!marked_[k]) continue;
      const std::uint32_t hi = vertex_[k];  // the upper corner until overwritten below
      const std::uint32_t lo = lower(k);
      const float d0 = field.values[lo] - iso, d1 = field.values[hi] - iso;
      const float t = std::clamp(d0 / (d0 - d1), 1e-3f, 1.0f - 1e-3f);
      vertices[v] = grid.corner_position(lo) * (1.0f - t) + grid.corner_position(hi) * t;
      segment_of_vertex_[v] = k;
      vertex_[k] = v++;
    }
  });
  return vertices;
}

}  // namespace meshflow
