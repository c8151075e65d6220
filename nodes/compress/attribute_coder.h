#pragma once
// The per-vertex attribute coders of a compressed mesh body (nodes/compress/mesh_codec.h). They
// run after the connectivity and the positions, so a decoder already holds the whole decoded
// geometry when it reads the attributes:
//  - normals: predicted by the area-weighted normal of the vertex's one ring of decoded faces
//    (from the integer grid positions; the previous decoded normal without a ring). The input
//    normal is quantised around the prediction itself: its azimuthal equidistant coordinates
//    in a tangent frame of the prediction (angle from it, towards it) on a square grid of a
//    stated step, so the error is bounded everywhere by step / sqrt(2) and a well predicted
//    normal costs a zero residual and keeps only the prediction's own (smaller) error. The two
//    residuals are range-coded in contexts of how flat the ring is and how large the position
//    grid's noise on the ring's normal is against the step. Meshes whose normals are
//    area-weighted face normals (the extractors') cost well under a bit per normal at 0.5
//    degrees.
//  - colours: nodes/compress/color_coder.h.
// Not thread-safe per coder; O(V + T).

#include <array>
#include <cstdint>
#include <string>
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

/// Codes `normals` (one per grid vertex, output order; unit or zero) around their predictions with
/// a residual grid of `step` radians (kMinNormalStep .. kMaxNormalStep; normal_step_for()): each
/// decoded normal is within step / sqrt(2) of its input's direction. Writes the step first.
/// Returns the normals the decoder will produce. O(V + T).
std::vector<Eigen::Vector3f> encode_normals(const DecodedGeometry& g,
                                            const std::vector<Eigen::Vector3f>& normals, float step,
                                            RangeEncoder& enc);

/// Reads what encode_normals() wrote for the same geometry. Throws Error naming `source` for a
/// step out of range. O(V + T).
std::vector<Eigen::Vector3f> decode_normals(const DecodedGeometry& g, RangeDecoder& dec,
                                            const std::string& source);

/// One normal `n` relative to a predicted unit normal `predicted` (the progressive splits' coder):
/// both in the frame of `predicted`, quantised with `bits`; returns the code difference and
/// sets `decoded` to what apply_normal_residual() gives. O(1).
std::array<std::int32_t, 2> normal_residual(const Eigen::Vector3f& predicted,
                                            const Eigen::Vector3f& n, unsigned bits,
                                            Eigen::Vector3f& decoded);

/// The normal of a residual from normal_residual() (codes clamped to the grid). O(1).
Eigen::Vector3f apply_normal_residual(const Eigen::Vector3f& predicted,
                                      const std::array<std::int32_t, 2>& residual, unsigned bits);

}  // namespace meshflow::compress
