#include "serve/mesh_stream.h"

#include <algorithm>

#include "nodes/compress/compressed_mesh.h"
#include "nodes/compress/mesh_codec.h"
#include "nodes/io/byte_buffer.h"

namespace meshflow::serve {

MeshStreamPlan plan_mesh_stream(const std::vector<unsigned char>& mfc, std::size_t chunk_bytes,
                                const std::string& source) {
  io::ByteReader in = compress::detail::body_reader(mfc, source);
  const compress::CompressedMeshInfo info = compress::detail::read_header(in, mfc);
  MeshStreamPlan plan;
  plan.vertices = info.vertices;
  plan.triangles = info.triangles;
  plan.progressive = info.kind == compress::CompressionKind::kProgressive;
  if (!plan.progressive) {
    plan.chunk_ends.push_back(mfc.size());
    return plan;
  }
  compress::decode_body(in, info.quantizer, {info.normals, info.colors}, source);
  in.u64("split count");
  const std::uint32_t packets = in.u32("packet count");
  plan.base_end = in.position();
  for (std::uint32_t p = 0; p < packets; ++p) {
    in.u32("packet split count");
    const std::uint64_t size = in.u64("packet size");
    in.bytes(static_cast<std::size_t>(size), "packet");
    plan.packet_ends.push_back(in.position());
  }
  chunk_bytes = std::max<std::size_t>(chunk_bytes, 1);
  plan.chunk_ends.push_back(plan.base_end);
  for (std::size_t end : plan.packet_ends)
    if (end - plan.chunk_ends.back() >= chunk_bytes) plan.chunk_ends.push_back(end);
  if (plan.chunk_ends.back() != mfc.size()) plan.chunk_ends.push_back(mfc.size());
  return plan;
}

}  // namespace meshflow::serve
