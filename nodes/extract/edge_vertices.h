#pragma once
// One shared vertex per crossed grid edge, numbered independently of the thread count. Used by
// every extraction method: cells mark the lattice segments their surface crosses, then vertices
// are numbered in table order and placed by linear interpolation of the field.

#include <cstdint>
#include <memory>
#include <vector>

#include "runtime/distance_field.h"
#include "runtime/sparse_grid.h"

namespace meshflow {

/// A table over lattice segments "corner i, direction d" (d < directions), each joining corner
/// i to a corner with larger coordinates. One byte per segment flags it (so the numbering pass
/// scans bytes, not words); the upper corner is stored for flagged segments only. Marking is
/// thread-safe (relaxed atomic stores: every cell sharing a segment writes the same values);
/// numbering runs after all marks, ordered after them by the join of the marking loop. Memory:
/// 5 bytes per segment (the vertex numbers overwrite the upper corners) and 8 per vertex.
class EdgeVertexTable {
 public:
  /// A table of corners x directions unmarked segments. O(corners x directions) bytes.
  EdgeVertexTable(std::size_t corners, std::size_t directions);

  /// Segment id of (lower corner, direction).
  std::size_t segment(std::uint32_t lower, std::size_t direction) const {
    return static_cast<std::size_t>(lower) * directions_ + direction;
  }
  /// Marks segment `s` as crossed; `upper` is its other corner. Thread-safe.
  void mark(std::size_t s, std::uint32_t upper) {
    __atomic_store_n(&upper_[s], upper, __ATOMIC_RELAXED);
    __atomic_store_n(&marked_[s], std::uint8_t{1}, __ATOMIC_RELAXED);
  }

  /// Numbers the marked segments in table order and returns one vertex per segment, at the
  /// iso-crossing of the linear interpolation between its corners (parameter clamped to
  /// [1e-3, 1 - 1e-3] so no two vertices coincide); upper() is no longer valid after it (the
  /// vertex numbers take the upper corners' place). Call once. Parallel over fixed blocks;
  /// O(table).
  std::vector<Eigen::Vector3f> place_vertices(const SparseGrid& grid, const DistanceField& field,
                                              float iso);

  /// Vertex of a marked segment (valid after place_vertices).
  std::uint32_t vertex(std::size_t s) const { return vertex_[s]; }
  /// The segment vertex v lies on (valid after place_vertices, until release_marks).
  std::size_t segment_of_vertex(std::uint32_t v) const { return segment_of_vertex_[v]; }
  /// Frees the marks and segment_of_vertex()'s table (9 bytes per vertex and one per segment)
  /// once only vertex() is needed. O(1).
  void release_marks() {
    marked_.reset();
    std::vector<std::size_t>().swap(segment_of_vertex_);
  }
  /// Direction of segment s.
  std::size_t direction(std::size_t s) const { return s % directions_; }
  /// Lower and upper corner of a marked segment.
  std::uint32_t lower(std::size_t s) const { return static_cast<std::uint32_t>(s / directions_); }
  /// Upper corner of a marked segment (valid before place_vertices).
  std::uint32_t upper(std::size_t s) const { return upper_[s]; }

 private:
  std::size_t directions_;
  std::size_t size_;
  // GCC/Clang __atomic builtins on plain arrays: atomic while marking, plain (vectorisable)
  // reads once the marking loop has joined.
  std::unique_ptr<std::uint8_t[]> marked_;
  std::unique_ptr<std::uint32_t[]> upper_;   // written for marked segments only
  std::unique_ptr<std::uint32_t[]> vertex_;  // upper_'s storage after place_vertices
  std::vector<std::size_t> segment_of_vertex_;
};

}  // namespace meshflow
