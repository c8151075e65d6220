#pragma once
// A mesh with one texture image per large planar region (the texture step's output, written as
// OBJ + MTL + PNG by io::write_textured_obj).

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "runtime/image.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {

struct RegionTexture {
  Image image;                       ///< RGB8, row 0 at the top
  std::vector<std::uint32_t> faces;  ///< the region's faces, ascending
};

struct TexturedMesh {
  TriangleMesh mesh;  ///< the input mesh, with per-vertex colours of the nearest point
  std::vector<RegionTexture> textures;
  std::vector<std::int32_t> texture_of_face;  ///< per face: index into textures, -1 = none
  /// Three per face (corner order), in [0, 1] with v pointing up the image; (0, 0) for faces
  /// without a texture.
  std::vector<Eigen::Vector2f> uv;
};

}  // namespace meshflow
