#pragma once
// The closed, manifold surface that Edgebreaker traverses, made from any triangle mesh:
//  - triangles with a repeated corner are set aside (stored verbatim by the coder);
//  - an edge is shared (its two half-edges twins) only when exactly two faces use it, in
//    opposite directions; every other edge (a border, a non-manifold edge, two faces with
//    opposite orientations) is cut;
//  - a vertex whose faces form several fans after the cuts (a non-manifold vertex, or one where
//    cut edges meet) becomes one surface vertex per fan, each naming its input vertex;
//  - every loop of cut edges is closed by a fan of triangles around one new "hole" vertex
//    (Rossignac's dummy vertex), so every half-edge has a twin.
// Decoding the surface and then dropping the hole vertices' triangles and merging the fans of
// one input vertex gives back the input's triangles exactly.

#include <cstdint>
#include <vector>

#include "runtime/triangle_mesh.h"

namespace meshflow::compress {

inline constexpr std::uint32_t kNone = 0xFFFFFFFFu;

/// Half-edge h = 3 t + i of triangle t runs from corner i to corner i + 1 (mod 3).
inline std::uint32_t next_half(std::uint32_t h) { return h % 3 == 2 ? h - 2 : h + 1; }
inline std::uint32_t prev_half(std::uint32_t h) { return h % 3 == 0 ? h + 2 : h - 1; }

struct ClosedSurface {
  /// Corner h's surface vertex (the origin of half-edge h); 3 per triangle, the input's
  /// surviving triangles first (in input order), then the hole fans.
  std::vector<std::uint32_t> corner_vertex;
  /// Half-edge h's twin (the same edge, reversed, in the adjacent triangle); never kNone.
  std::vector<std::uint32_t> twin;
  /// Per surface vertex: the input vertex, or kNone for a hole vertex.
  std::vector<std::uint32_t> input_vertex;
  /// Per surface triangle: its input triangle, or kNone for a hole-fan triangle.
  std::vector<std::uint32_t> input_triangle;
  /// Input triangles with a repeated corner, in input order (not on the surface).
  std::vector<std::uint32_t> degenerate_triangles;
  std::uint32_t hole_count = 0;  ///< loops of cut edges closed by a hole vertex

  /// Triangles of the surface (input's and hole fans').
  std::size_t triangle_count() const { return corner_vertex.size() / 3; }
  /// Vertices of the surface (fans and hole vertices).
  std::size_t vertex_count() const { return input_vertex.size(); }
};

/// Builds the closed surface of `triangles` (corners index vertices; any range). O(T log T)
/// for the edge sort, O(T) otherwise; serial.
ClosedSurface build_closed_surface(const std::vector<Triangle>& triangles);

}  // namespace meshflow::compress
