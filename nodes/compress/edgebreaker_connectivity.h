#pragma once
// Edgebreaker (Rossignac 1999) on a closed surface (nodes/compress/closed_surface.h): a
// depth-first walk over the triangles that writes one symbol per triangle, saying where its
// third vertex is relative to the active loops (the borders of the region walked so far):
//   C  a new vertex;            L  the vertex before the gate;   R  the vertex after the gate;
//   E  the loop is this triangle (it closes);   S  elsewhere on the loop (it splits in two);
//   M  on a loop waiting on the stack (a handle: the two loops merge).
// The decoder (nodes/compress/edgebreaker_replay.h) undoes the symbols last first on the same
// loop structure, so an S needs no offset; every M stores its other loop's place and length.

#include <cstdint>
#include <vector>

#include "nodes/compress/closed_surface.h"
#include "runtime/triangle_mesh.h"

namespace meshflow::compress {

enum class Op : std::uint8_t { kC = 0, kL = 1, kR = 2, kS = 3, kE = 4, kM = 5 };
inline constexpr unsigned kOpCount = 6;

/// An M symbol's other loop: `depth` loops below the top of the stack, `length` nodes long,
/// its vertex `offset` nodes after the loop's gate.
struct HandleRecord {
  std::uint32_t depth = 0;
  std::uint32_t offset = 0;
  std::uint32_t length = 0;
};

/// Everything the decoder needs to rebuild the surface's triangles.
struct Connectivity {
  std::uint32_t components = 0;       ///< each starts with a triangle of three new vertices
  std::vector<Op> ops;                ///< one per triangle after each component's first
  std::vector<HandleRecord> handles;  ///< one per M, in order
};

/// A vertex's position predictors (decoded vertex numbers, kNone where absent): the gate's ends
/// a and b and the vertex w across the gate (parallelogram a + b - w). A component's first
/// three vertices have (none), (first) and (first, second).
struct VertexPredictors {
  std::uint32_t a = kNone, b = kNone, w = kNone;
};

/// An edge (x, y) of a replayed surface and the third vertices `left` and `right` of its two
/// triangles (decoded vertex numbers): the parallelogram x + y - left predicts right and
/// x + y - right predicts left.
struct EdgeDiamond {
  std::uint32_t x, y, left, right;
};

/// What replaying the connectivity gives (the walk's vertex numbers and triangle order).
struct ReplayedSurface {
  std::uint32_t vertex_count = 0;            ///< decoded vertices, numbered in order of creation
  std::vector<Triangle> triangles;           ///< in decoding order
  std::vector<VertexPredictors> predictors;  ///< per decoded vertex
  std::vector<EdgeDiamond> diamonds;         ///< every edge once, in replay order
};

/// The encoder's walk.
struct Traversal {
  Connectivity connectivity;
  std::vector<std::uint32_t> surface_vertex;        ///< per decoded vertex: the surface vertex
  std::vector<std::uint32_t> surface_triangle;      ///< per decoded triangle: the surface triangle
  std::vector<std::size_t> component_first_symbol;  ///< per component: its first symbol's index
};

/// Walks every component of `surface` (starting each at its lowest-numbered triangle) and
/// returns the symbols. The decoded triangle k is surface triangle surface_triangle[k] with
/// corners rotated so that it starts at the gate's end; its vertices are decoded vertex numbers
/// that surface_vertex maps back. O(T log T) (splitting a loop walks its shorter part); serial.
Traversal edgebreaker_traverse(const ClosedSurface& surface);

}  // namespace meshflow::compress
