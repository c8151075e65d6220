#pragma once
// The parallelograms a decoder can form for a vertex (the idea of Draco's constrained
// multi-parallelogram scheme, written afresh): one parallelogram x + y - w per edge (x, y) whose
// two triangles' third vertices are the vertex k and a vertex w, with x, y and w all decoded
// before k. The codec (nodes/compress/mesh_codec.cpp) predicts a vertex by the mean of the ones
// the encoder flags as trusted. Built from the replay's edge diamonds
// (nodes/compress/edgebreaker_replay.h), which the decoder holds in full before it reads any
// position: no adjacency search.

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "nodes/compress/edgebreaker_connectivity.h"

namespace meshflow::compress {

/// Per decoded vertex, the edges that offer it a parallelogram. Immutable after construction:
/// safe to share between threads.
class ParallelogramRing {
 public:
  /// `diamonds`: every edge of the replayed surface once (corners are decoded vertex numbers <
  /// `vertices`); `hole[v]` != 0 marks vertices that carry no position (they never predict).
  /// O(V + E) time and memory (48 bytes per vertex).
  ParallelogramRing(const std::vector<EdgeDiamond>& diamonds, const std::vector<char>& hole,
                    std::size_t vertices);

  /// At most this many parallelograms per vertex are offered (the first in replay order).
  static constexpr unsigned kMaxParallelograms = 4;
  using Parallelograms = std::array<std::array<std::int64_t, 3>, kMaxParallelograms>;

  /// Writes to out[0 .. n) the parallelograms available to vertex `k` (x, y, w below k and not
  /// holes, read from `grid`), in an order both coder sides share, and returns n (<=
  /// kMaxParallelograms). O(n).
  unsigned gather(std::uint32_t k, const std::vector<std::array<std::int32_t, 3>>& grid,
                  Parallelograms& out) const {
    const unsigned count = count_[k];
    const Corners* c = corners_.get() + std::size_t{k} * kMaxParallelograms;
    for (unsigned i = 0; i < count; ++i) {
      const auto &x = grid[c[i].x], &y = grid[c[i].y], &w = grid[c[i].w];
      for (std::size_t a = 0; a < 3; ++a) out[i][a] = std::int64_t{x[a]} + y[a] - w[a];
    }
    return count;
  }

  /// Writes to out[0 .. 2 n) the shared-edge corners x and y of vertex `k`'s n parallelograms
  /// (gather()'s order; decoded neighbours of k, numbered below k) and returns 2 n. O(n).
  unsigned sides(std::uint32_t k, std::uint32_t* out) const {
    const unsigned count = count_[k];
    const Corners* c = corners_.get() + std::size_t{k} * kMaxParallelograms;
    for (unsigned i = 0; i < count; ++i) {
      out[2 * i] = c[i].x;
      out[2 * i + 1] = c[i].y;
    }
    return 2 * count;
  }

 private:
  struct Corners {
    std::uint32_t x, y, w;
  };
  std::vector<std::uint8_t> count_;  // per vertex: parallelograms offered (<= 4)
  // kMaxParallelograms slots per vertex, the first count_ set (no clearing: 48 bytes a vertex).
  std::unique_ptr<Corners[]> corners_;
};

}  // namespace meshflow::compress
