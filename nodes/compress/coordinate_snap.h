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

/// The decoded neighbours of a vertex whose coordinates it may equal: the ring's parallelogram
/// corners and the gate's vertices (ids may repeat). Filled by gather_snap_neighbours().
struct SnapNeighbours {
  static constexpr unsigned kMax = 3 * ParallelogramRing::kMaxParallelograms + 3;
  std::array<std::uint32_t, kMax> id{};
  unsigned count = 0;
};

/// The neighbours of decoded vertex `k`: its ring corners and those of its gate predictors `p`
/// that exist and are not holes (`hole`, per decoded vertex). Every id is below k. O(1).
SnapNeighbours gather_snap_neighbours(std::uint32_t k, const VertexPredictors& p,
                                      const ParallelogramRing& ring, const std::vector<char>& hole);

/// Up to kSnapCandidates distinct coordinate values, ordered by distance from the prediction
/// (the smaller value first on a tie).
inline constexpr unsigned kSnapCandidates = 4;
struct SnapCandidates {
  std::array<std::int32_t, kSnapCandidates> value{};
  unsigned n = 0;
};

/// The candidates on `axis` (0 .. 2) for a coordinate predicted at `predicted`, from the
/// neighbours' grid positions. Both coder sides call it with the same decoded data. O(count).
SnapCandidates snap_candidates(const SnapNeighbours& nb,
                               const std::vector<std::array<std::int32_t, 3>>& grid,
                               std::size_t axis, std::int32_t predicted);

/// Whether some neighbour's grid coordinate on `axis` is `value` (the encoder's guess that the
/// coordinate will snap). O(count).
inline bool shares_value(const SnapNeighbours& nb,
                         const std::vector<std::array<std::int32_t, 3>>& grid, std::size_t axis,
                         std::int32_t value) {
  bool shared = false;
  for (unsigned i = 0; i < nb.count; ++i) shared |= grid[nb.id[i]][axis] == value;
  return shared;
}

/// The snap symbols' adaptive models, per axis and context: the candidate count, whether the
/// nearest candidate is the prediction itself, how many of the vertex's earlier axes snapped (a
/// lattice vertex has one free coordinate) and whether the previous vertex snapped on the axis.
/// Axes are coded 0, 1, 2 for each vertex. Not thread-safe; one per position section.
class SnapModels {
 public:
  /// Codes which candidate `value` equals (or none) on `axis` for a coordinate predicted at
  /// `predicted`; returns true if one did (the coordinate is then coded), false if the caller
  /// must code its residual. Nothing is coded without candidates. O(1).
  bool encode(RangeEncoder& enc, std::size_t axis, const SnapCandidates& c, std::int32_t predicted,
              std::int32_t value);
  /// The decoder's side: sets `value` and returns true when the stream names a candidate; false
  /// when the residual follows. A corrupt symbol past the candidates reads as none. O(1).
  bool decode(RangeDecoderCore& dec, std::size_t axis, const SnapCandidates& c,
              std::int32_t predicted, std::int32_t& value);

 private:
  static constexpr unsigned kContexts = kSnapCandidates * 2 * 3 * 2;
  // The model of `axis` with c.n > 0 candidates.
  FrequencyModel<8>& model(std::size_t axis, const SnapCandidates& c, std::int32_t predicted) {
    const unsigned exact = c.value[0] == predicted;
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
