#pragma once
// The browser's decoder: a C API over nodes/compress (compiled to WebAssembly by emscripten for
// the page, natively for the tests, from the same sources). It decodes a .mfc image or a prefix
// of a progressive one that ends between split packets (serve/mesh_stream.h says where), and
// keeps the last decoded mesh for the page to copy out. Not thread-safe (one decoder state).

#include <cstddef>
#include <cstdint>

extern "C" {

/// Decodes `data[0, size)`. `packets` < 0: a complete image (checksum checked). Otherwise a
/// prefix of a progressive image holding its base (`base_end` bytes: header, base body, split
/// and packet counts) and its first `packets` split packets: it is decoded as that level of
/// detail. Returns 0 on success, -1 on an error (mf_error() says which).
int mf_decode(const unsigned char* data, std::size_t size, std::size_t base_end, int packets);

/// The last decoded mesh (valid until the next mf_decode).
std::uint32_t mf_vertex_count();
std::uint32_t mf_triangle_count();
const float* mf_positions();        ///< x, y, z per vertex
const std::uint32_t* mf_indices();  ///< three corners per triangle
const float* mf_normals();          ///< x, y, z per vertex, or null
const std::uint8_t* mf_colors();    ///< r, g, b per vertex, or null
/// The message of the last error ("" after a success).
const char* mf_error();
}
