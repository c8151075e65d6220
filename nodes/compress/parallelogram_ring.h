#pragma once
// Multi-parallelogram position prediction (the idea of Draco's multi-parallelogram schemes,
// written afresh): a vertex is predicted by the mean of every parallelogram x + y - w the
// decoder can already form, one per triangle (k, x, y) at the vertex whose far edge (x, y) is
// shared with a triangle (y, x, w) and whose x, y and w were all decoded before k. Built from the
// replayed connectivity, which the decoder holds in full before it reads any position.

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

  /// Sums into `sum` the parallelograms available to vertex `k` (corners below k and not holes,
  /// read from `grid`), sets `spread` to their largest minus smallest value per axis (how much
  /// they disagree) and returns how many there are (0: both zero). O(valence^2).
  unsigned sum(std::uint32_t k, const std::vector<std::array<std::int32_t, 3>>& grid,
               std::array<std::int64_t, 3>& sum, std::array<std::int64_t, 3>& spread) const;

 private:
  // The vertex opposite the directed edge from -> to in a triangle holding to -> from, or kNone.
  std::uint32_t across(std::uint32_t from, std::uint32_t to) const;

  const std::vector<Triangle>& triangles_;
  const std::vector<char>& hole_;
  std::vector<std::uint32_t> first_;     // per vertex + 1: offsets into incident_
  std::vector<std::uint32_t> incident_;  // triangle numbers, grouped by vertex
};

}  // namespace meshflow::compress
