#include "nodes/compress/coordinate_snap.h"

namespace meshflow::compress {

SnapNeighbours gather_snap_neighbours(std::uint32_t k, const VertexPredictors& p,
                                      const ParallelogramRing& ring,
                                      const std::vector<char>& hole) {
  SnapNeighbours nb;
  nb.count = ring.corners(k, nb.id.data());
  for (std::uint32_t v : {p.a, p.b, p.w})
    if (v != kNone && v < k && !hole[v]) nb.id[nb.count++] = v;
  return nb;
}

SnapCandidates snap_candidates(const SnapNeighbours& nb,
                               const std::vector<std::array<std::int32_t, 3>>& grid,
                               std::size_t axis, std::int32_t predicted) {
  SnapCandidates c;
  std::array<std::int64_t, kSnapCandidates> key{};  // distance * 2^32 + value order
  for (unsigned i = 0; i < nb.count; ++i) {
    const std::int32_t v = grid[nb.id[i]][axis];
    bool seen = false;
    for (unsigned j = 0; j < c.n; ++j) seen |= c.value[j] == v;
    if (seen) continue;
    const std::int64_t d = std::int64_t{v} - predicted;
    // Ties in distance: the smaller value first (it is the one below the prediction).
    const std::int64_t k = ((d < 0 ? -d : d) << 1) | (d > 0 ? 1 : 0);
    unsigned at = c.n < kSnapCandidates ? c.n : kSnapCandidates;
    while (at > 0 && key[at - 1] > k) --at;
    if (at >= kSnapCandidates) continue;
    for (unsigned j = (c.n < kSnapCandidates ? c.n : kSnapCandidates - 1); j > at; --j) {
      key[j] = key[j - 1];
      c.value[j] = c.value[j - 1];
    }
    key[at] = k;
    c.value[at] = v;
    if (c.n < kSnapCandidates) ++c.n;
  }
  return c;
}

bool SnapModels::encode(RangeEncoder& enc, std::size_t axis, const SnapCandidates& c,
                        std::int32_t predicted, std::int32_t value) {
  if (axis == 0) earlier_ = 0;
  if (c.n == 0) return false;
  unsigned symbol = 0;
  for (unsigned j = 0; j < c.n; ++j)
    if (c.value[j] == value) {
      symbol = j + 1;
      break;
    }
  model(axis, c, predicted).encode(enc, symbol);
  record(axis, symbol != 0);
  return symbol != 0;
}

bool SnapModels::decode(RangeDecoderCore& dec, std::size_t axis, const SnapCandidates& c,
                        std::int32_t predicted, std::int32_t& value) {
  if (axis == 0) earlier_ = 0;
  if (c.n == 0) return false;
  const unsigned symbol = model(axis, c, predicted).decode(dec);
  const bool snapped = symbol != 0 && symbol <= c.n;
  record(axis, snapped);
  if (snapped) value = c.value[symbol - 1];
  return snapped;
}

}  // namespace meshflow::compress
