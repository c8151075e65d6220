#include "web/mfc_decoder.h"

#include <exception>
#include <string>
#include <vector>

#include "nodes/compress/compressed_mesh.h"
#include "nodes/compress/progressive_mesh.h"
#include "nodes/io/byte_buffer.h"
#include "runtime/triangle_mesh.h"

namespace {

meshflow::TriangleMesh g_mesh;
std::string g_error;

}  // namespace

extern "C" {

int mf_decode(const unsigned char* data, std::size_t size, std::size_t base_end, int packets) {
  using namespace meshflow;
  g_error.clear();
  try {
    if (packets < 0) {
      g_mesh = compress::decompress_mesh(std::vector<unsigned char>(data, data + size), "stream");
      return 0;
    }
    if (base_end < 4 || base_end > size) {
      g_error = "stream: the prefix does not hold the base mesh";
      return -1;
    }
    // The prefix as an image of its own: the packets it holds, and a checksum of its bytes.
    std::vector<unsigned char> image(data, data + size);
    for (int b = 0; b < 4; ++b)
      image[base_end - 4 + static_cast<std::size_t>(b)] =
          static_cast<unsigned char>(static_cast<std::uint32_t>(packets) >> (8 * b));
    image.resize(size + 8);
    io::reseal_fnv1a64(image.data(), image.size());
    g_mesh = compress::decompress_progressive_level(image, "stream", compress::ProgressiveLevel{});
    return 0;
  } catch (const std::exception& e) {
    g_mesh = TriangleMesh{};
    g_error = e.what();
    return -1;
  }
}

std::uint32_t mf_vertex_count() { return static_cast<std::uint32_t>(g_mesh.vertices.size()); }

std::uint32_t mf_triangle_count() { return static_cast<std::uint32_t>(g_mesh.triangles.size()); }

const float* mf_positions() {
  return g_mesh.vertices.empty() ? nullptr : g_mesh.vertices[0].data();
}

const std::uint32_t* mf_indices() {
  return g_mesh.triangles.empty() ? nullptr : g_mesh.triangles[0].data();
}

const float* mf_normals() { return g_mesh.normals.empty() ? nullptr : g_mesh.normals[0].data(); }

const std::uint8_t* mf_colors() { return g_mesh.colors.empty() ? nullptr : &g_mesh.colors[0].r; }

const char* mf_error() { return g_error.c_str(); }
}
