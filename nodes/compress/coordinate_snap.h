#pragma once
// Lattice snapping of grid coordinates (position coder, nodes/compress/mesh_codec.cpp). The
// meshes meshflow's extractors write lie on the edges of a voxel lattice: two of each vertex's
// three coordinates are lattice values its neighbours share exactly (about two thirds of all
// coordinates on reconstructed meshes). Per axis the coder first says which of the few
// distinct values the vertex's decoded neighbours have on that axis (nearest the prediction
// first) the coordinate equals, or none (one symbol for the three axes); only a coordinate equal
// to none of them codes its residual. A symbol of about a bit then replaces a residual of four
// to five bits.

#include <array>
#include <cstdint>
#include <vector>

#include "nodes/compress/edgebreaker_connectivity.h"
#include "nodes/compress/parallelogram_ring.h"
#include "nodes/compress/range_coder.h"

namespace meshflow::compress {

/// The distinct decoded neighbours of a vertex whose coordinates it may equal (the shared-edge
/// corners x and y of the ring's parallelograms and the gate's vertices a and b, each once; not
/// the far corners w: version 10 left them out, which made files 2.5-3.4 % smaller and the
/// decoder 6 % faster): their grid coordinates per axis. Filled by SnapNeighbourhood::gather().
struct SnapNeighbours {
  static constexpr unsigned kMax = 2 * ParallelogramRing::kMaxParallelograms + 2;
  std::array<std::array<std::int32_t, kMax>, 3> coordinate{};  ///< [axis][neighbour]
  unsigned count = 0;
};

/// Gathers a vertex's SnapNeighbours, each neighbour once (a stamp per vertex drops repeats).
/// Not thread-safe; one per position section. O(V) memory.
class SnapNeighbourhood {
 public:
  /// For a surface of `vertices` decoded vertices.
  explicit SnapNeighbourhood(std::size_t vertices) : stamp_(vertices, kNone) {}
  /// The neighbours of decoded vertex `k`: its ring's shared-edge corners and those of its gate
  /// vertices p.a and p.b that exist, come before k and are not holes (`hole`, per decoded
  /// vertex), with their positions in `grid` (decoded before k). Valid until the next call. O(1).
  const SnapNeighbours& gather(std::uint32_t k, const VertexPredictors& p,
                               const ParallelogramRing& ring, const std::vector<char>& hole,
                               const std::vector<std::array<std::int32_t, 3>>& grid) {
    std::uint32_t id[SnapNeighbours::kMax];
    unsigned n = ring.sides(k, id);
    for (std::uint32_t v : {p.a, p.b})
      if (v != kNone && v < k && !hole[v]) id[n++] = v;
    nb_.count = 0;
    for (unsigned i = 0; i < n; ++i) {
      const std::uint32_t v = id[i];
      if (stamp_[v] == k) continue;
      stamp_[v] = k;
      const std::array<std::int32_t, 3>& g = grid[v];
      for (std::size_t a = 0; a < 3; ++a) nb_.coordinate[a][nb_.count] = g[a];
      ++nb_.count;
    }
    return nb_;
  }

 private:
  std::vector<std::uint32_t> stamp_;  // per decoded vertex: the last k that gathered it
  SnapNeighbours nb_;
};

/// A coordinate's snap candidates: the distinct neighbour values on its axis ranked by distance
/// from the prediction (the smaller value first on a tie); the kSnapCandidates nearest are
/// offered. Both coder sides rank the same decoded data.
inline constexpr unsigned kSnapCandidates = 4;
struct SnapCandidates {
  // Only [0, distinct) is set (no clearing: a coder builds three per vertex).
  std::array<std::int32_t, SnapNeighbours::kMax> value;      ///< distinct, in neighbour order
  std::array<std::uint64_t, SnapNeighbours::kMax> rank_key;  ///< key() of each value
  unsigned distinct = 0;
  unsigned n = 0;            ///< offered: min(distinct, kSnapCandidates)
  std::int32_t nearest = 0;  ///< the value of rank 0 (when n > 0)
  std::int32_t predicted = 0;

  /// The rank order's key of value v: distance from the prediction, the side below first.
  std::uint64_t key(std::int32_t v) const {
    const std::int64_t d = std::int64_t{v} - predicted;
    return (static_cast<std::uint64_t>(d < 0 ? -d : d) << 1) | (d > 0 ? 1u : 0u);
  }
  /// The value of rank r < n. O(distinct^2) (distinct is small; a decoder asks only for a
  /// snap past the nearest candidate).
  std::int32_t ranked(unsigned r) const;
  /// The snap symbol of `v`: 1 + its rank when it is one of the n offered, else 0. O(distinct).
  unsigned symbol_of(std::int32_t v) const;
};

/// The candidates on `axis` (0 .. 2) for a coordinate predicted at `predicted`. O(count x
/// distinct).
inline SnapCandidates snap_candidates(const SnapNeighbours& nb, std::size_t axis,
                                      std::int32_t predicted) {
  SnapCandidates c;
  c.predicted = predicted;
  const std::int32_t* in = nb.coordinate[axis].data();
  // Locals, not c's members, in the loop: the compiler keeps them in registers.
  std::uint64_t best = ~std::uint64_t{0};
  std::int32_t nearest = 0;
  unsigned distinct = 0;
  for (unsigned i = 0; i < nb.count; ++i) {
    const std::int32_t v = in[i];
    bool seen = false;
    for (unsigned j = 0; j < distinct; ++j) seen |= c.value[j] == v;
    if (seen) continue;
    const std::uint64_t k = c.key(v);
    c.rank_key[distinct] = k;
    c.value[distinct++] = v;
    nearest = k < best ? v : nearest;
    best = k < best ? k : best;
  }
  c.distinct = distinct;
  c.nearest = nearest;
  c.n = distinct < kSnapCandidates ? distinct : kSnapCandidates;
  return c;
}

/// Whether some neighbour's grid coordinate on `axis` is `value` (the encoder's guess that the
/// coordinate will snap). O(count).
inline bool shares_value(const SnapNeighbours& nb, std::size_t axis, std::int32_t value) {
  bool shared = false;
  for (unsigned i = 0; i < nb.count; ++i) shared |= nb.coordinate[axis][i] == value;
  return shared;
}

/// The snap symbols' adaptive models: one joint symbol per vertex (version 11) saying, for its
/// three axes at once, whether each coordinate is none of its candidates (0), the nearest (1),
/// the second (2) or a later one (3; with four offered, an adaptive bit tells the third from
/// the fourth); context: per axis the candidate count (0, 1, 2, 3 or more) and whether the
/// nearest candidate is the prediction itself. One range-coder step instead of three: the axes
/// of a lattice vertex snap together (two of three), which the joint symbol also learns. Not
/// thread-safe; one per position section.
class SnapModels {
 public:
  using Axes = std::array<SnapCandidates, 3>;
  /// Codes which candidate each of `value`'s coordinates equals (or none) and returns the mask
  /// of those that did (bit a: axis a; those coordinates are then coded), the others' residuals
  /// being the caller's. Nothing is coded when no axis has candidates. O(distinct).
  unsigned encode(RangeEncoder& enc, const Axes& c, const std::array<std::int32_t, 3>& value);
  /// The decoder's side: sets the snapped coordinates of `value` and returns their mask. A
  /// corrupt symbol naming a rank past an axis's candidates reads as none. O(1) for none or the
  /// nearest candidate, O(distinct^2) past it.
  [[gnu::always_inline]] unsigned decode(RangeDecoderCore& dec, const Axes& c,
                                         std::array<std::int32_t, 3>& value) {
    const unsigned context = state(c[0]) + kStates * (state(c[1]) + kStates * state(c[2]));
    if (context == 0) return 0;  // no candidates on any axis
    const unsigned symbol = joint_[context].decode(dec);
    unsigned mask = 0;
    for (unsigned a = 0; a < 3; ++a) {
      unsigned rank = (symbol >> (2 * a)) & 3u;
      if (rank == 0) continue;
      if (rank == 3 && c[a].n == kSnapCandidates) rank += dec.decode(fourth_);
      if (rank > c[a].n) continue;
      value[a] = rank == 1 ? c[a].nearest : c[a].ranked(rank - 1);
      mask |= 1u << a;
    }
    return mask;
  }

 private:
  // Per axis: 0 without candidates, else 1 + 2 (min(n, 3) - 1) + (nearest == prediction).
  static constexpr unsigned kStates = 7, kContexts = kStates * kStates * kStates;
  static unsigned state(const SnapCandidates& c) {
    if (c.n == 0) return 0;
    return 1 + 2 * ((c.n < 3 ? c.n : 3) - 1) + (c.nearest == c.predicted ? 1u : 0u);
  }
  std::vector<FrequencyModel<64>> joint_ = std::vector<FrequencyModel<64>>(kContexts);
  BitModel fourth_;  // rank 4 (1) or 3 (0) where four candidates are offered
};

}  // namespace meshflow::compress
