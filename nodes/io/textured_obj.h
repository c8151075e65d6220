#pragma once
// Wavefront OBJ with materials and PNG textures, for meshes textured by
// texture_planar_regions.

#include <string>

#include "runtime/textured_mesh.h"

namespace meshflow::io {

/// Writes PATH (.obj), its material library beside it (PATH's stem + ".mtl") and one PNG per
/// texture (stem + "_region" + index + ".png"). Vertices carry their colours ("v x y z r g b",
/// read by MeshLab and CloudCompare); faces without a texture use the material
/// "vertex_colours", the others "region<k>" with texture coordinates. Every file is written
/// atomically; throws meshflow::Error on I/O failure. O(V + T + texels).
void write_textured_obj(const std::string& path, const TexturedMesh& mesh);

}  // namespace meshflow::io
