#pragma once
// The single-rate body of a compressed mesh: Edgebreaker connectivity, positions predicted on
// the quantisation grid by the mean of the parallelograms the encoder flags as trusted among
// those the decoder can form (nodes/compress/parallelogram_ring.h; constrained
// multi-parallelogram prediction),
// normals and colours predicted from the decoded geometry (nodes/compress/attribute_coder.h,
// color_coder.h), all range-coded. The container (header, checksum) is compressed_mesh.h's;
// the progressive format stores its base mesh as such a body.
//
// Body layout (little-endian): u32 components, u64 symbols, u64 surface vertices, then six
// sections, each a u64 byte count and a range-coded stream: side data (handles, hole vertices,
// merged fans, degenerate triangles, vertices off the surface), symbols (CLERS + M, last first,
// context: the rebuilt triangles at the gate's vertices and the symbol after; see
// nodes/compress/edgebreaker_replay.h), positions x, y and z (one stream per axis, so that a
// decoder's three dependency chains overlap; each vertex's trusted subset of the offered
// parallelograms, one choice, precedes its x residual); then a u8 of octahedral normal bits (0
// without normals; the progressive splits' grid) and the attribute section (with normals their
// residual step, a float's 32 bits at even odds, and the normals; then colours: their channel
// order in 3 bits and three int8 coefficients at even odds, and the residuals).

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "nodes/compress/quantizer.h"
#include "nodes/io/byte_buffer.h"
#include "runtime/triangle_mesh.h"

namespace meshflow::compress {

/// Which per-vertex attributes a body carries.
struct AttributeFlags {
  bool normals = false;
  bool colors = false;
  /// Encoding only: octahedral bits per normal coordinate (kMinNormalBits .. kMaxNormalBits);
  /// a decoder reads them from the body.
  unsigned normal_bits = kDefaultNormalBits;
  /// Encoding only: the single-rate normal coder's residual step, radians (from kMinNormalStep
  /// to kMaxNormalStep; normal_step_for()); a decoder reads it from the attribute section.
  float normal_step = normal_step_for(normal_error_degrees(kDefaultNormalBits));
  /// File level: the body stores no normals and the decoder recomputes them (header flag bit 2).
  bool recomputed_normals = false;
};

/// Sizes and counts of one encoded body.
struct BodyStats {
  std::size_t connectivity_bytes = 0;  ///< symbols + side data
  std::size_t position_bytes = 0;
  std::size_t attribute_bytes = 0;
  std::size_t symbols = 0;
  std::size_t holes = 0;                   ///< loops of border (or cut) edges closed for the walk
  std::size_t handles = 0;                 ///< M symbols
  std::size_t merged_fans = 0;             ///< extra fans of non-manifold vertices
  std::size_t offered_parallelograms = 0;  ///< parallelograms the ring offered, all vertices
  std::size_t trusted_parallelograms = 0;  ///< of which the encoder flagged as trusted
  std::size_t snapped_coordinates = 0;  ///< coordinates coded as a neighbour's (coordinate_snap.h)
};

/// Where each output vertex and triangle of a decoded body came from.
struct BodyOrder {
  std::vector<std::uint32_t> vertex;    ///< decoded vertex k is input vertex vertex[k]
  std::vector<std::uint32_t> triangle;  ///< decoded triangle k is input triangle triangle[k]
};

/// The integer codes of a decoded body's vertices (output order), for coders that continue
/// from them (the progressive splits): float positions do not always quantise back exactly.
struct BodyCodes {
  std::vector<std::array<std::int32_t, 3>> positions;
  std::vector<Eigen::Vector3f> normals;  ///< as decoded; empty without normals
  unsigned normal_bits = 0;              ///< octahedral bits of the normals (0: none)
};

/// Appends the body of `mesh` to `out`. Vertices come out in the order the walk meets them, then
/// those on no triangle (input order); triangles in walk order, then those with a repeated
/// corner; each triangle keeps its orientation (it may start at another corner). Corners must
/// be in range. `codes`, if given, receives what decode_body() will give. O(T log T); serial.
BodyStats encode_body(const TriangleMesh& mesh, const Quantizer& quantizer, AttributeFlags flags,
                      io::ByteWriter& out, BodyOrder* order = nullptr, BodyCodes* codes = nullptr);

/// Reads a body written by encode_body() with the same quantiser and flags. Throws Error naming
/// `source` and the field for truncated or inconsistent data. Runs what needs only the
/// connectivity beside the positions, and the colours' neighbour weights beside the normals, on
/// a second thread where oneTBB has one (nodes/compress/side_by_side.h): the same mesh and the
/// same error at any thread count. O(T log T).
TriangleMesh decode_body(io::ByteReader& in, const Quantizer& quantizer, AttributeFlags flags,
                         const std::string& source, BodyCodes* codes = nullptr);

}  // namespace meshflow::compress
