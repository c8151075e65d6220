#pragma once
// Texture generation for planar regions (the reconstruction thesis's optimisation stage): every
// large planar region gets one image, rendered in its plane from the coloured input points
// (nearest point per texel), with texture coordinates for its faces; everything else keeps
// per-vertex colours. Written as OBJ + MTL + PNG by io::write_textured_obj.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "runtime/planar_segmentation.h"
#include "runtime/point_cloud.h"
#include "runtime/textured_mesh.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {

struct TextureConfig {
  float texel_size = 0.01f;     ///< metres per texel (grown for regions beyond max_texture_size)
  int max_texture_size = 2048;  ///< texels along the longer side, at most
  std::size_t min_region_faces = 200;  ///< smaller regions keep vertex colours
  /// Texels farther than this (metres) from every coloured point are grey: no colour was seen
  /// there.
  float max_distance = 0.05f;
};

/// Renders the textures of the regions of `segmentation` (made on HalfEdgeMesh(mesh)) with at
/// least min_region_faces faces from `points` (which must have colours; throws
/// meshflow::Error otherwise) and colours every vertex by its nearest point. Texels are the
/// points of the region's plane on a texel_size grid over the bounding rectangle of its
/// vertices' projections. Parallel over texel rows and vertices; deterministic.
/// O(texels x log points + V log points).
TexturedMesh texture_planar_regions(const TriangleMesh& mesh,
                                    const PlanarSegmentation& segmentation,
                                    const PointCloud& points, const TextureConfig& config = {});

}  // namespace meshflow
