#include "nodes/compress/coordinate_snap.h"

namespace meshflow::compress {

std::int32_t SnapCandidates::ranked(unsigned r) const {
  for (unsigned i = 0; i < distinct; ++i) {
    const std::uint64_t k = rank_key[i];
    unsigned below = 0;
    for (unsigned j = 0; j < distinct; ++j) below += rank_key[j] < k ? 1u : 0u;
    if (below == r) return value[i];
  }
  return nearest;  // not reached for r < n
}

unsigned SnapCandidates::symbol_of(std::int32_t v) const {
  bool present = false;
  for (unsigned i = 0; i < distinct; ++i) present |= value[i] == v;
  if (!present) return 0;
  const std::uint64_t k = key(v);
  unsigned below = 0;
  for (unsigned i = 0; i < distinct; ++i) below += rank_key[i] < k ? 1u : 0u;
  return below < n ? below + 1 : 0;
}

bool SnapModels::encode(RangeEncoder& enc, std::size_t axis, const SnapCandidates& c,
                        std::int32_t value) {
  if (axis == 0) earlier_ = 0;
  if (c.n == 0) return false;
  const unsigned symbol = c.symbol_of(value);
  model(axis, c).encode(enc, symbol);
  record(axis, symbol != 0);
  return symbol != 0;
}

}  // namespace meshflow::compress
