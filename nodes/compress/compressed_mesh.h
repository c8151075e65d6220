#pragma once
// meshflow's compressed mesh files (".mfc"): one triangle mesh, coded single-rate (Edgebreaker)
// or progressively (a base mesh and vertex splits). Format, version 11, little-endian:
//
//   bytes 0-7   magic "MFMESH\r\n"
//   u32         version (11; 10 coded the snap symbols axis by axis, 9 also offered the
//               parallelograms' far corners as snap candidates, 8 predicted colours by the plain
//               mean of the decoded neighbours and coded YCoCg-R residuals, 7 coded every
//               coordinate as a residual, without the snap symbols of
//               nodes/compress/coordinate_snap.h, 6 coded normals on an octahedral grid, 5 coded
//               symbols, residual lengths and trust flags bit by bit, 4 had a position mode byte
//               and no trust flags, 3 no position mode byte, 2 no prefix checksums and coded
//               attributes from one neighbour)
//   u32         kind: 1 = Edgebreaker, 2 = progressive
//   u32         flags: bit 0 per-vertex normals stored, bit 1 per-vertex colours, bit 2 normals
//               not stored: the decoder recomputes them from the decoded geometry
//   u64         vertices, u64 triangles (of the full mesh)
//   f64 x 3     quantisation origin (metres), f64 step (metres, > 0), u32 bits (1 .. 30)
//   u64         progressive: the prefix checksum, FNV-1a 64 of the bytes up to the end of the
//               packet count (this field read as zero); single-rate: 0
//   ...         kind 1: one body (nodes/compress/mesh_codec.h);
//               kind 2: the base mesh's body, then packets of vertex splits, each ending in a
//               checksum chained from the one before (nodes/compress/progressive_mesh.h)
//   u64         FNV-1a 64 hash of every byte before it
//
// So every prefix of a progressive file that ends at a packet boundary is checked and decodes to
// the levels it holds (decompress_progressive_prefix()). A decoded position is within step / 2
// of the input's on each axis; normals within the stated angle (0.25 degrees at the default 10
// bits; CompressConfig::normal_bits, normal_error); colours exact; triangles exactly the input's
// (each may start at another corner), vertices and triangles reordered (the encoder reports the
// order).

#include <cstdint>
#include <string>
#include <vector>

#include "nodes/compress/mesh_codec.h"
#include "runtime/triangle_mesh.h"

namespace meshflow::compress {

enum class CompressionKind : std::uint32_t { kEdgebreaker = 1, kProgressive = 2 };

struct CompressConfig {
  /// Quantisation step, metres; 0 = 1/64 of the mesh's median edge length (for meshes from the
  /// extractors, whose edges are about a voxel: positions move by under 1 % of a voxel).
  double step = 0.0;
  /// If > 0 (1 .. 30): the bounding box's longest side in 2^bits - 1 steps, overriding `step`.
  unsigned position_bits = 0;
  bool normals = true;  ///< keep the mesh's normals if it has them
  /// Octahedral bits per normal coordinate (kMinNormalBits .. kMaxNormalBits; the default is
  /// Draco's default grid, within 0.26 degrees), or 0: store none and have the decoder recompute
  /// them as area-weighted face normals of the decoded geometry (exact for meshes whose normals
  /// were made that way, the extractors'; any other normals come back as the surface's).
  unsigned normal_bits = kDefaultNormalBits;
  /// If > 0: the largest angle (degrees, 0.001 .. 30) between an input normal and its decoded
  /// normal, overriding normal_bits' bound (normal_error_degrees()); the progressive splits take
  /// the fewest octahedral bits whose bound is within it. Ignored when normal_bits is 0.
  double normal_error = 0.0;
  bool colors = true;  ///< store the mesh's colours if it has them
  /// Progressive only: the base mesh is decimated to this share of the triangles (QEM; it may
  /// stop above it where no valid collapse is left).
  float base_ratio = 0.02f;
  /// Added to every position (metres, double precision) as it is stored: for meshes kept in a
  /// local frame (Frame::origin), so that the decoded mesh is in world coordinates.
  Eigen::Vector3d origin_offset = Eigen::Vector3d::Zero();
  /// Progressive only: vertex splits per packet (each packet decodes on its own, so a prefix
  /// of the file gives a level of detail).
  std::uint32_t splits_per_packet = 4096;
};

/// What one encoding gave.
struct CompressReport {
  CompressionKind kind = CompressionKind::kEdgebreaker;
  std::size_t total_bytes = 0;
  BodyStats body;  ///< the (base) mesh's body
  Quantizer quantizer;
  std::size_t base_triangles = 0;  ///< progressive: the base mesh's triangles
  std::size_t base_bytes = 0;      ///< progressive: bytes up to the end of the base mesh
  std::size_t splits = 0;          ///< progressive: vertex splits
  /// Output vertex k is input vertex vertex_order[k]; output triangle k is input triangle
  /// triangle_order[k] (progressive: at full detail).
  std::vector<std::uint32_t> vertex_order, triangle_order;
};

/// The quantiser `config` gives for `mesh` (bounding box origin, step, bits; without
/// origin_offset). Throws Error for non-finite positions or a corner out of range. O(V + T).
Quantizer choose_quantizer(const TriangleMesh& mesh, const CompressConfig& config);

/// Encodes `mesh` single-rate (Edgebreaker). Throws Error for a corner out of range or a
/// non-finite position. O(T log T); serial (frames in flight compress in parallel).
std::vector<unsigned char> compress_mesh(const TriangleMesh& mesh,
                                         const CompressConfig& config = {},
                                         CompressReport* report = nullptr);

/// What a file's header says.
struct CompressedMeshInfo {
  std::uint32_t version = 0;
  CompressionKind kind = CompressionKind::kEdgebreaker;
  bool normals = false, colors = false;
  bool recomputed_normals = false;  ///< the decoder recomputes the normals (flag bit 2)
  std::uint64_t vertices = 0, triangles = 0;
  std::uint64_t prefix_checksum = 0;  ///< progressive: FNV-1a of the base prefix
  Quantizer quantizer;
};

/// Decodes a single-rate or progressive image (the full mesh). `source` names the data in
/// errors. Throws Error naming the field for a wrong magic or version, truncation, a checksum
/// mismatch or inconsistent contents. O(T log T).
TriangleMesh decompress_mesh(const std::vector<unsigned char>& bytes, const std::string& source);

/// Reads and checks the header (and the file checksum). Throws Error as decompress_mesh();
/// the version error names the version found and the one this build reads.
CompressedMeshInfo compressed_mesh_info(const std::vector<unsigned char>& bytes,
                                        const std::string& source);

/// Rewrites the checksum (the last 8 bytes) to match the bytes before it, for the fuzzers and
/// tests that corrupt fields on purpose. No effect below 8 bytes.
void reseal_compressed_mesh(std::vector<unsigned char>& bytes);

namespace detail {
/// The attributes `config` stores for `mesh` (those it has, per vertex).
AttributeFlags attribute_flags(const TriangleMesh& mesh, const CompressConfig& config);
/// Writes the header of a `kind` file (everything before the body); the stored origin is the
/// quantiser's plus `offset`.
void write_header(io::ByteWriter& out, CompressionKind kind, AttributeFlags flags,
                  std::uint64_t vertices, std::uint64_t triangles, const Quantizer& quantizer,
                  const Eigen::Vector3d& offset);
/// Checks magic, version, checksum and reads the header; leaves `in` at the body. With
/// `check_file_checksum` false (prefixes of progressive files) the trailing checksum is not read.
CompressedMeshInfo read_header(io::ByteReader& in, const std::vector<unsigned char>& bytes,
                               bool check_file_checksum = true);
/// Byte offset of the prefix checksum field in the header.
inline constexpr std::size_t kPrefixChecksumOffset = 72;
/// FNV-1a 64 continued from `hash` over data[0, n) (fnv1a64 is this from its offset basis).
std::uint64_t fnv1a64_continue(std::uint64_t hash, const unsigned char* data, std::size_t n);
/// The prefix checksum of bytes[0, end) (the field at kPrefixChecksumOffset read as zero).
std::uint64_t prefix_checksum(const unsigned char* bytes, std::size_t end);
/// The normals a decoder gives a file with flag bit 2: area-weighted face normals of the
/// decoded grid positions `grid` (per vertex of `mesh`).
void recompute_normals(TriangleMesh& mesh, const std::vector<std::array<std::int32_t, 3>>& grid);
/// A reader over `bytes` without their checksum (the body's end), `source` naming them (it
/// must outlive the reader).
io::ByteReader body_reader(const std::vector<unsigned char>& bytes, const std::string& source);
/// Appends the checksum.
void seal(io::ByteWriter& out);
}  // namespace detail

}  // namespace meshflow::compress
