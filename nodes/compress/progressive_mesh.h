#pragma once
// Progressive meshes (Hoppe 1996) on meshflow's QEM decimation: the mesh is decimated by
// half-edge collapses u -> v (nodes/decimate), the coarse result is stored as an Edgebreaker
// body (the base mesh M0), and the collapses, last first, as vertex splits: split k turns M(k)
// into M(k+1) by bringing back u and the triangles the collapse removed. Any prefix of the
// splits is a level of detail; all of them give the input's triangles exactly.
//
// After the base body (compressed_mesh.h's kind 2):
//   u64 split count, u32 packet count, then each packet: u32 splits, u64 bytes (the stream and
//   its checksum), a range-coded stream (fresh models per packet, so each decodes on its own
//   once those before it have), and u64 FNV-1a 64 of the packet's header and stream continued
//   from the checksum before (the header's prefix checksum for the first packet);
//   then u64 triangles with a repeated corner (added at full detail only) and their corners.
// One split: v (the surviving vertex, direct bits), u's grid position relative to v's, u's
// normal relative to v's (in v's normal's frame: attribute_coder.h) and colour relative to v's, one
// bit per triangle around v (ordered by their other two vertices) saying whether it goes to u, the
// number of triangles brought back, and for each its third vertex (its rank among v's neighbours,
// or an escape and the vertex) and the order of its corners.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "nodes/compress/compressed_mesh.h"
#include "nodes/io/byte_buffer.h"

namespace meshflow::compress {

/// How much of a progressive mesh to decode.
struct ProgressiveLevel {
  /// Apply at most this many vertex splits (0: the base mesh).
  std::size_t splits = std::numeric_limits<std::size_t>::max();
  /// Stop after the first split that reaches this many triangles.
  std::size_t triangles = std::numeric_limits<std::size_t>::max();
};

/// Encodes `mesh` progressively (config.base_ratio, config.splits_per_packet). The report's
/// base_bytes is the prefix a receiver needs for the base mesh. Throws Error for a corner out
/// of range or a non-finite position. O(T log T) plus the decimation's cost; the decimation
/// runs in parallel, the coding serially.
std::vector<unsigned char> compress_progressive(const TriangleMesh& mesh,
                                                const CompressConfig& config = {},
                                                CompressReport* report = nullptr);

/// compress_progressive() keeping the vertices `locked` flags (one per vertex of `mesh`, nonzero:
/// locked) through every level: no collapse removes one, so each is in the base mesh, at its
/// quantised position like every vertex (other vertices may collapse onto it). Locking every
/// vertex of a border keeps that border's edges in every level (a tile's seams, so neighbouring
/// tiles' levels meet: graph/tile_levels.h). Empty `locked`: compress_progressive(mesh, config,
/// report), the same bytes. Throws Error as it does, and for a `locked` of another size than the
/// vertices. Same cost.
std::vector<unsigned char> compress_progressive(const TriangleMesh& mesh,
                                                const std::vector<std::uint8_t>& locked,
                                                const CompressConfig& config = {},
                                                CompressReport* report = nullptr);

/// Decoding a prefix of a progressive image: the image's first byte (to check the prefix
/// checksum against), and what was found.
struct PrefixState {
  const unsigned char* image = nullptr;
  std::size_t packets_read = 0, packets_stated = 0;
  bool complete = false;          ///< the image went on to the end of the file's data
  bool stopped_at_level = false;  ///< the level asked for was reached before the data's end
};

/// Decodes the level `level` of a progressive image (header already read into `info`; `in`
/// at the base body). Each packet's checksum is checked as it is read. Without the full level,
/// the data after the last split decoded is not read. With `prefix`, the prefix checksum is
/// checked and the data may end at any packet boundary (the level then stops there). Throws
/// Error naming the field for inconsistent data or a checksum mismatch. O(T log T).
TriangleMesh decode_progressive(io::ByteReader& in, const CompressedMeshInfo& info,
                                const std::string& source, const ProgressiveLevel& level,
                                PrefixState* prefix = nullptr);

/// What decompress_progressive_prefix() gave.
struct PrefixDecode {
  TriangleMesh mesh;
  std::size_t packets = 0;         ///< split packets the prefix held (and that were applied)
  std::size_t packets_stated = 0;  ///< split packets in the whole file
  bool complete = false;           ///< the whole file (or the level asked for) was decoded
};

/// Decodes a prefix of a progressive file (a network stream's first bytes): the whole file, or
/// the header and base mesh and any number of whole split packets (cut at a packet boundary),
/// to the level it holds (at most `level`). The prefix checksum and every packet's checksum are
/// checked, so a flipped byte anywhere is reported. Throws Error naming the field for a
/// mismatch, a cut inside the base or a packet, or a single-rate file. O(T log T).
PrefixDecode decompress_progressive_prefix(const std::vector<unsigned char>& bytes,
                                           const std::string& source,
                                           const ProgressiveLevel& level = {});

/// For fuzzers and tests that corrupt fields on purpose: rewrites every checksum of a
/// progressive image (the prefix checksum, each packet's, the file's) to match the bytes, as
/// far as the image's lengths can be followed (stops at the first length that leaves the data).
/// Single-rate or unreadable images get the file checksum only (reseal_compressed_mesh()).
/// O(size); changes nothing but checksum fields.
void reseal_progressive_mesh(std::vector<unsigned char>& bytes);

/// Decodes a level of a progressive file image (checksum checked). Throws Error.
TriangleMesh decompress_progressive_level(const std::vector<unsigned char>& bytes,
                                          const std::string& source, const ProgressiveLevel& level);

}  // namespace meshflow::compress
