#pragma once
// Mesh writers: PLY (binary little-endian or ascii) and Wavefront OBJ.

#include <string>

#include "runtime/triangle_mesh.h"

namespace meshflow::io {

enum class PlyEncoding { kBinary, kAscii };

/// Writes vertices (float x y z), normals (nx ny nz) and colours (uchar red green blue) when
/// present, and faces (uchar count, uint vertex_indices). Atomic: the file appears complete
/// or not at all. Throws meshflow::Error on I/O failure. O(V + T).
void write_ply(const std::string& path, const TriangleMesh& mesh,
               PlyEncoding encoding = PlyEncoding::kBinary);

/// Writes v / vn / f lines (1-based indices, "f a//a b//b c//c" when normals exist). Atomic.
void write_obj(const std::string& path, const TriangleMesh& mesh);

/// Chooses the writer by extension (.ply binary, .obj); throws meshflow::Error otherwise.
void write_mesh(const std::string& path, const TriangleMesh& mesh);

}  // namespace meshflow::io
