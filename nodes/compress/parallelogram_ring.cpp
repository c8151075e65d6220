#include "nodes/compress/parallelogram_ring.h"

#include <algorithm>

namespace meshflow::compress {

ParallelogramRing::ParallelogramRing(const std::vector<EdgeDiamond>& diamonds,
                                     const std::vector<char>& hole, std::size_t vertices)
    : first_(vertices + 1, 0) {
  // The vertex an edge predicts (kNone: none): the later of its two third vertices, if the
  // edge's ends and the earlier one come before it and none is a hole.
  const auto predicted = [&](const EdgeDiamond& d) {
    const std::uint32_t k = std::max(d.left, d.right), w = std::min(d.left, d.right);
    if (k >= vertices || d.x >= k || d.y >= k || w == k) return kNone;
    if (hole[k] || hole[d.x] || hole[d.y] || hole[w]) return kNone;
    return k;
  };
  std::vector<std::uint32_t> target(diamonds.size());
  for (std::size_t i = 0; i < diamonds.size(); ++i) {
    const std::uint32_t k = predicted(diamonds[i]);
    target[i] = k;
    if (k != kNone && first_[k + 1] < kMaxParallelograms) ++first_[k + 1];
  }
  for (std::size_t v = 0; v < vertices; ++v) first_[v + 1] += first_[v];
  corners_.resize(first_[vertices]);
  std::vector<std::uint32_t> fill(first_.begin(), first_.end() - 1);
  for (std::size_t i = 0; i < diamonds.size(); ++i) {
    const std::uint32_t k = target[i];
    if (k == kNone || fill[k] == first_[k + 1]) continue;  // none, or four taken already
    const EdgeDiamond& d = diamonds[i];
    corners_[fill[k]++] = {d.x, d.y, std::min(d.left, d.right)};
  }
}

}  // namespace meshflow::compress
