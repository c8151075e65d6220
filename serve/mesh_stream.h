#pragma once
// How a .mfc image (nodes/compress/compressed_mesh.h) is cut for streaming: a progressive
// image's first chunk ends after the base mesh and the split and packet counts, every later cut
// falls between whole split packets, so a receiver holding any chunk prefix can decode a level
// of detail (web/mfc_wasm.cpp: the prefix with its packet count set to the packets it holds,
// resealed). A single-rate (Edgebreaker) image is one piece: it decodes only when complete.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace meshflow::serve {

struct MeshStreamPlan {
  bool progressive = false;
  std::uint64_t vertices = 0, triangles = 0;  ///< of the full mesh (the header's counts)
  /// Progressive: bytes up to and including the u32 packet count (the base mesh's prefix).
  std::size_t base_end = 0;
  /// Progressive: the end offset of each split packet, in order.
  std::vector<std::size_t> packet_ends;
  /// Where the chunks end; the last is the image's size.
  std::vector<std::size_t> chunk_ends;
};

/// Reads the layout of `mfc` (header, checksum, and for a progressive image the base body and
/// the packet headers) and cuts it into chunks of about `chunk_bytes` (the base chunk may be
/// larger). Throws meshflow::Error naming `source` for an invalid image. O(base mesh + packets).
MeshStreamPlan plan_mesh_stream(const std::vector<unsigned char>& mfc, std::size_t chunk_bytes,
                                const std::string& source = "published mesh");

}  // namespace meshflow::serve
