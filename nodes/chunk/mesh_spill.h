#pragma once
// A finished chunk's mesh spilled to disk until the weld's plan (which needs every chunk's seam
// summary) says where its rows go in the output: the out-of-core path then holds the chunks in
// flight, not the output mesh.

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/triangle_mesh.h"

namespace meshflow::chunk {

/// What a chunk keeps for weld_chunk() (seam_weld.h) besides its seam summary.
struct SpilledMesh {
  TriangleMesh mesh;
  std::vector<std::uint8_t> flags;          ///< one byte per vertex, or empty
  std::vector<std::uint32_t> vertex_piece;  ///< ChunkSeams::vertex_piece
};

/// Writes `spilled` to `path` (created or replaced; raw little-endian arrays behind their
/// counts). Throws meshflow::Error naming `path` and the system's reason. O(V + T).
void write_mesh_spill(const std::string& path, const SpilledMesh& spilled);

/// Reads write_mesh_spill()'s file back. Throws meshflow::Error naming `path` for a missing or
/// short file. O(V + T).
SpilledMesh read_mesh_spill(const std::string& path);

}  // namespace meshflow::chunk
