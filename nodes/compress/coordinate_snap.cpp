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

unsigned SnapModels::encode(RangeEncoder& enc, const Axes& c,
                            const std::array<std::int32_t, 3>& value) {
  const unsigned context = state(c[0]) + kStates * (state(c[1]) + kStates * state(c[2]));
  if (context == 0) return 0;
  std::array<unsigned, 3> rank{};
  unsigned symbol = 0, mask = 0;
  for (unsigned a = 0; a < 3; ++a) {
    rank[a] = c[a].n == 0 ? 0u : c[a].symbol_of(value[a]);
    symbol |= (rank[a] < 3 ? rank[a] : 3u) << (2 * a);
    mask |= rank[a] != 0 ? 1u << a : 0u;
  }
  joint_[context].encode(enc, symbol);
  for (unsigned a = 0; a < 3; ++a)
    if (rank[a] >= 3 && c[a].n == kSnapCandidates) enc.encode(fourth_, rank[a] - 3);
  return mask;
}

}  // namespace meshflow::compress
