#pragma once
// Lattice snapping of grid coordinates (position coder, nodes/compress/mesh_codec.cpp). The
// meshes meshflow's extractors write lie on the edges of a voxel lattice: two of each vertex's
// three coordinates are lattice values its neighbours share exactly (about two thirds of all
// coordinates on reconstructed meshes). Per axis the coder first says which of the few
// distinct values the vertex's decoded neighbours have on that axis (nearest the prediction
// first) the coordinate equals, or none; only a coordinate equal to none of them codes its
// residual. A symbol of about a bit then replaces a residual of four to five bits.

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

/// The snap symbols' adaptive models, per axis and context: the candidate count, whether the
/// nearest candidate is the prediction itself, how many of the vertex's earlier axes snapped (a
/// lattice vertex has one free coordinate) and whether the previous vertex snapped on the axis.
/// Axes are coded 0, 1, 2 for each vertex. Not thread-safe; one per position section.
class SnapModels {
 public:
  /// Codes which candidate `value` equals (or none) on `axis`; returns true if one did (the
  /// coordinate is then coded), false if the caller must code its residual. Nothing is coded
  /// without candidates. O(distinct).
  bool encode(RangeEncoder& enc, std::size_t axis, const SnapCandidates& c, std::int32_t value);
  /// The decoder's side: sets `value` and returns true when the stream names a candidate; false
  /// when the residual follows. A corrupt symbol past the candidates reads as none. O(1) for
  /// none or the nearest candidate, O(distinct^2) past it.
  bool decode(RangeDecoderCore& dec, std::size_t axis, const SnapCandidates& c,
              std::int32_t& value) {
    if (axis == 0) earlier_ = 0;
    if (c.n == 0) return false;
    const unsigned symbol = model(axis, c).decode(dec);
    const bool snapped = symbol != 0 && symbol <= c.n;
    record(axis, snapped);
    if (snapped) value = symbol == 1 ? c.nearest : c.ranked(symbol - 1);
    return snapped;
  }

 private:
  static constexpr unsigned kContexts = kSnapCandidates * 2 * 3 * 2;
  // The model of `axis` with c.n > 0 candidates.
  FrequencyModel<8>& model(std::size_t axis, const SnapCandidates& c) {
    const unsigned exact = c.nearest == c.predicted;
    return symbol_[axis][(((c.n - 1) * 2 + exact) * 3 + earlier_) * 2 + last_[axis]];
  }
  void record(std::size_t axis, bool snapped) {
    last_[axis] = snapped;
    earlier_ += snapped;
  }
  std::array<std::array<FrequencyModel<8>, kContexts>, 3> symbol_{};
  std::array<unsigned, 3> last_{};  // per axis: the previous coded vertex snapped (1) or not
  unsigned earlier_ = 0;            // this vertex's axes before the current one that snapped
};

}  // namespace meshflow::compress
