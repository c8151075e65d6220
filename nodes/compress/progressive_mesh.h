#pragma once
// Progressive meshes (Hoppe 1996) on meshflow's QEM decimation: the mesh is decimated by
// half-edge collapses u -> v (nodes/decimate), the coarse result is stored as an Edgebreaker
// body (the base mesh M0), and the collapses, last first, as vertex splits: split k turns M(k)
// into M(k+1) by bringing back u and the triangles the collapse removed. Any prefix of the
// splits is a level of detail; all of them give the input's triangles exactly.
//
// After the base body (compressed_mesh.h's kind 2):
//   u64 split count, u32 packet count, then each packet: u32 splits, u64 bytes, a range-coded
//   stream (fresh models per packet, so each decodes on its own once those before it have);
//   then u64 triangles with a repeated corner (added at full detail only) and their corners.
// One split: v (the surviving vertex, direct bits), u's grid position relative to v's, u's
// normal and colour relative to v's, one bit per triangle around v (ordered by their other two
// vertices) saying whether it goes to u, the number of triangles brought back, and for each
// its third vertex (its rank among v's neighbours, or an escape and the vertex) and the order
// of its corners.

#include <cstddef>
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

/// Decodes the level `level` of a progressive image (header already read into `info`; `in`
/// at the base body). Without the full level, the data after the last split decoded is not
/// read. Throws Error naming the field for inconsistent data. O(T log T).
TriangleMesh decode_progressive(io::ByteReader& in, const CompressedMeshInfo& info,
                                const std::string& source, const ProgressiveLevel& level);

/// Decodes a level of a progressive file image (checksum checked). Throws Error.
TriangleMesh decompress_progressive_level(const std::vector<unsigned char>& bytes,
                                          const std::string& source, const ProgressiveLevel& level);

}  // namespace meshflow::compress
