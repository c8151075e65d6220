#include "nodes/compress/parallelogram_ring.h"

#include <algorithm>

namespace meshflow::compress {

ParallelogramRing::ParallelogramRing(const std::vector<EdgeDiamond>& diamonds,
                                     const std::vector<char>& hole, std::size_t vertices)
    : count_(vertices, 0), corners_(new Corners[vertices * kMaxParallelograms]) {
  // Each edge predicts the later of its two third vertices, k, if the edge's ends and the
  // earlier one w come before k and none is a hole.
  for (const EdgeDiamond& d : diamonds) {
    const std::uint32_t k = std::max(d.left, d.right), w = std::min(d.left, d.right);
    if (k >= vertices || d.x >= k || d.y >= k || w == k) continue;
    if ((hole[k] | hole[d.x] | hole[d.y] | hole[w]) != 0) continue;
    std::uint8_t& n = count_[k];
    if (n < kMaxParallelograms) corners_[std::size_t{k} * kMaxParallelograms + n++] = {d.x, d.y, w};
  }
}

}  // namespace meshflow::compress
