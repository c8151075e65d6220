#pragma once
// glTF 2.0 binary (.glb) reader: the meshes meshflow writes (glb_writer.h) and those of other
// exporters that keep their geometry in the file's own binary chunk.

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/triangle_mesh.h"

namespace meshflow::io {

/// Decodes .glb bytes into one mesh: every triangle primitive (mode 4, the default) of every
/// mesh, in file order, concatenated. Reads POSITION (float VEC3), NORMAL (float VEC3) and
/// COLOR_0 (VEC3 or VEC4, float or normalized unsigned byte / short; alpha dropped), each kept
/// only when every primitive has it, and indices (unsigned byte, short or int; a primitive
/// without indices takes its vertices three by three). Buffer views may be strided. Positions
/// are as stored: node transforms (a georeferenced mesh's translation) are not applied.
/// Throws meshflow::Error naming `source` and the JSON field or byte offset for a wrong magic,
/// version or chunk, a buffer outside the binary chunk, an accessor type it does not read,
/// sparse accessors, external buffer URIs, a non-triangle primitive, an index out of range, a
/// non-integer or negative count / offset / index field, or accessors decoding more than 16
/// times the binary chunk (shared by that many primitives). O(file size).
TriangleMesh decode_glb(const std::vector<unsigned char>& bytes, const std::string& source);

/// decode_glb() of the file at `path`. Throws meshflow::Error naming the file.
TriangleMesh read_glb_mesh(const std::string& path);

}  // namespace meshflow::io
