#pragma once
// The per-vertex attribute coders of a compressed mesh body (nodes/compress/mesh_codec.h). Both
// run after the connectivity and the positions, so a decoder already holds the whole decoded
// geometry when it reads the attributes:
//  - normals: predicted by the area-weighted normal of the vertex's one ring of decoded faces
//    (from the integer grid positions: exact and identical on every platform); the input
//    normal and the prediction are mapped into a frame whose +z is the prediction's dominant
//    axis (a signed axis permutation: exact), quantised there on the octahedron, and the
//    difference of the two codes is range-coded in one of five contexts chosen by how flat the
//    ring is (its faces' normals agreeing or not). Meshes whose normals are area-weighted face
//    normals (the extractors') cost about 1-3 bits per normal.
//  - colours: predicted by the mean of the vertex's one-ring neighbours decoded before it (the
//    previous vertex's colour without any), both mapped to YCoCg-R (reversible on integers), and
//    the three differences range-coded, Co and Cg in contexts of the size of Y's difference.
//    Exact at 8 bits.
// Not thread-safe per coder; O(V + T).

#include <array>
#include <cstdint>
#include <vector>

#include "nodes/compress/range_coder.h"
#include "runtime/triangle_mesh.h"

namespace meshflow::compress {

/// Decoded geometry the attribute coders predict from: integer grid positions per output vertex
/// and the output triangles (corners < grid.size(); each may start at any corner).
struct DecodedGeometry {
  const std::vector<std::array<std::int32_t, 3>>& grid;
  const std::vector<Triangle>& triangles;
};

/// Area-weighted one-ring face normal sums per vertex, from the grid (exact integer cross
/// products, summed in double in triangle order: bit-identical wherever the triangles come in
/// the same order). Zero for a vertex on no non-degenerate triangle. O(V + T).
std::vector<std::array<double, 3>> ring_normal_sums(const DecodedGeometry& g);

/// The unit normals the decoder gives when a file carries none but asks for them: the
/// normalised ring sums, +z where a vertex has none. O(V + T).
std::vector<Eigen::Vector3f> recomputed_normals(const DecodedGeometry& g);

/// Codes `normals` (one per grid vertex, output order) with `bits` octahedral bits. Returns the
/// normals the decoder will produce. O(V + T).
std::vector<Eigen::Vector3f> encode_normals(const DecodedGeometry& g,
                                            const std::vector<Eigen::Vector3f>& normals,
                                            unsigned bits, RangeEncoder& enc);

/// Reads what encode_normals() wrote for the same geometry and bits. O(V + T).
std::vector<Eigen::Vector3f> decode_normals(const DecodedGeometry& g, unsigned bits,
                                            RangeDecoder& dec);

/// One normal `n` relative to a predicted unit normal `predicted` (the progressive splits' coder):
/// both in the frame of `predicted`, quantised with `bits`; returns the code difference and
/// sets `decoded` to what apply_normal_residual() gives. O(1).
std::array<std::int32_t, 2> normal_residual(const Eigen::Vector3f& predicted,
                                            const Eigen::Vector3f& n, unsigned bits,
                                            Eigen::Vector3f& decoded);

/// The normal of a residual from normal_residual() (codes clamped to the grid). O(1).
Eigen::Vector3f apply_normal_residual(const Eigen::Vector3f& predicted,
                                      const std::array<std::int32_t, 2>& residual, unsigned bits);

/// Codes `colors` (one per grid vertex, output order), exactly. O(V + T).
void encode_colors(const DecodedGeometry& g, const std::vector<Rgb8>& colors, RangeEncoder& enc);

/// Reads what encode_colors() wrote for the same geometry. O(V + T).
std::vector<Rgb8> decode_colors(const DecodedGeometry& g, RangeDecoder& dec);

}  // namespace meshflow::compress
