#pragma once
// glTF 2.0 binary (.glb): the mesh viewers, game engines and web pages load directly.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "runtime/triangle_mesh.h"

namespace meshflow::io {

/// The .glb bytes of `mesh`: one scene, one node, one triangle primitive with POSITION (float,
/// with the min/max bounds glTF requires), NORMAL (unit length; a zero normal becomes +z) and
/// COLOR_0 (normalized unsigned-byte RGBA) where the mesh has them, and 32-bit indices. The
/// JSON chunk is written with nlohmann-json. Coordinates are kept as they are (metres; glTF's
/// +Y-up convention is the viewer's concern). Throws meshflow::Error for a mesh without
/// triangles (glTF accessors cannot be empty). A non-zero `origin` (georeferenced meshes) is the
/// node's translation. O(V + T).
std::vector<std::uint8_t> encode_glb(const TriangleMesh& mesh,
                                     const Eigen::Vector3d& origin = Eigen::Vector3d::Zero());

/// encode_glb() written atomically to `path`. Throws meshflow::Error naming the file.
void write_glb(const std::string& path, const TriangleMesh& mesh,
               const Eigen::Vector3d& origin = Eigen::Vector3d::Zero());

}  // namespace meshflow::io
