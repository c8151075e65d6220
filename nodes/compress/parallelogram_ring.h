#pragma once
// The parallelograms a decoder can form for a vertex (the idea of Draco's constrained
// multi-parallelogram scheme, written afresh): one parallelogram x + y - w per triangle (k, x, y)
// at the vertex whose far edge (x, y) is shared with a triangle (y, x, w) and whose x, y and w
// were all decoded before k. The codec (nodes/compress/mesh_codec.cpp) predicts a vertex by the
// mean of the ones the encoder flags as trusted. Built from the replayed connectivity, which the
// decoder holds in full before it reads any position.

#include <array>
#include <cstdint>
#include <vector>

#include "runtime/triangle_mesh.h"

namespace meshflow::compress {

/// Vertex-to-triangle incidence of a replayed surface, for multi-parallelogram prediction.
/// Immutable after construction: safe to share between threads.
class ParallelogramRing {
 public:
  /// `triangles`: corners are decoded vertex numbers < `vertices`; `hole[v]` != 0 marks vertices
  /// that carry no position (they never predict). O(V + T) time and memory.
  ParallelogramRing(const std::vector<Triangle>& triangles, const std::vector<char>& hole,
                    std::size_t vertices);

  /// At most this many parallelograms per vertex are offered (the first in incidence order).
  static constexpr unsigned kMaxParallelograms = 4;
  using Parallelograms = std::array<std::array<std::int64_t, 3>, kMaxParallelograms>;

  /// Writes to out[0 .. n) the parallelograms available to vertex `k` (corners below k and not
  /// holes, read from `grid`), in an order both coder sides share, and returns n (<=
  /// kMaxParallelograms). O(valence^2).
  unsigned gather(std::uint32_t k, const std::vector<std::array<std::int32_t, 3>>& grid,
                  Parallelograms& out) const;

 private:
  // The vertex opposite the directed edge from -> to in a triangle holding to -> from, or kNone.
  std::uint32_t across(std::uint32_t from, std::uint32_t to) const;

  // One triangle at a vertex v: its corners after v, in the triangle's order (v, next, prev).
  struct RingEdge {
    std::uint32_t next, prev;
  };

  const std::vector<char>& hole_;
  std::vector<std::uint32_t> first_;  // per vertex + 1: offsets into incident_
  std::vector<RingEdge> incident_;    // grouped by vertex, in triangle order (contiguous scans)
};

}  // namespace meshflow::compress
