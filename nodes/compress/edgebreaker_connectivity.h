#pragma once
// Edgebreaker (Rossignac 1999) on a closed surface (nodes/compress/closed_surface.h): a
// depth-first walk over the triangles that writes one symbol per triangle, saying where its
// third vertex is relative to the active loops (the borders of the region walked so far):
//   C  a new vertex;            L  the vertex before the gate;   R  the vertex after the gate;
//   E  the loop is this triangle (it closes);   S  elsewhere on the loop (it splits in two);
//   M  on a loop waiting on the stack (a handle: the two loops merge).
// The decoder replays the symbols on the same loop structure. An S's vertex is found from the
// string alone (its right branch has to close a loop of the length the symbols in it consume;
// Rossignac's offset rule); the encoder checks the rule against the walk and stores the few
// offsets it gets wrong (after M symbols) explicitly, and every M its loop and offset.

#include <cstdint>
#include <string>
#include <vector>

#include "nodes/compress/closed_surface.h"
#include "runtime/triangle_mesh.h"

namespace meshflow::compress {

enum class Op : std::uint8_t { kC = 0, kL = 1, kR = 2, kS = 3, kE = 4, kM = 5 };
inline constexpr unsigned kOpCount = 6;

/// An M symbol's other loop: `depth` loops below the top of the stack, its vertex `offset`
/// nodes after the loop's gate.
struct HandleRecord {
  std::uint32_t depth = 0;
  std::uint32_t offset = 0;
};

/// An S symbol (counted from 0 among the S symbols) whose vertex is `offset` nodes after the
/// gate's end, where the offset rule predicts otherwise.
struct SplitOffset {
  std::uint32_t split = 0;
  std::uint32_t offset = 0;
};

/// Everything the decoder needs to rebuild the surface's triangles.
struct Connectivity {
  std::uint32_t components = 0;            ///< each starts with a triangle of three new vertices
  std::vector<Op> ops;                     ///< one per triangle after each component's first
  std::vector<HandleRecord> handles;       ///< one per M, in order
  std::vector<SplitOffset> split_offsets;  ///< in increasing split order
};

/// A vertex's position predictors (decoded vertex numbers, kNone where absent): the gate's ends
/// a and b and the vertex w across the gate (parallelogram a + b - w). A component's first
/// three vertices have (none), (first) and (first, second).
struct VertexPredictors {
  std::uint32_t a = kNone, b = kNone, w = kNone;
};

/// What replaying the connectivity gives.
struct ReplayedSurface {
  std::uint32_t vertex_count = 0;            ///< decoded vertices, numbered in order of creation
  std::vector<Triangle> triangles;           ///< in decoding order
  std::vector<VertexPredictors> predictors;  ///< per decoded vertex
};

/// The encoder's walk.
struct Traversal {
  Connectivity connectivity;
  std::vector<std::uint32_t> surface_vertex;    ///< per decoded vertex: the surface vertex
  std::vector<std::uint32_t> surface_triangle;  ///< per decoded triangle: the surface triangle
};

/// Walks every component of `surface` (starting each at its lowest-numbered triangle) and
/// returns the symbols. The decoded triangle k is surface triangle surface_triangle[k] with
/// corners rotated so that it starts at the gate's end; its vertices are decoded vertex numbers
/// that surface_vertex maps back. O(T log T) (splitting a loop walks its shorter part); serial.
Traversal edgebreaker_traverse(const ClosedSurface& surface);

/// The offset of every S symbol's vertex that Rossignac's rule predicts from the symbols alone
/// (-1 where it predicts none). O(number of symbols).
std::vector<std::int64_t> predicted_split_offsets(const std::vector<Op>& ops);

/// Rebuilds the triangles from the connectivity. Throws Error(source, "connectivity", ...) for
/// symbols that do not describe a surface (a loop closed that is not a triangle, an offset past
/// its loop, symbols left over or missing). O(T log T).
ReplayedSurface edgebreaker_replay(const Connectivity& connectivity, const std::string& source);

}  // namespace meshflow::compress
