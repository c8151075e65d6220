#pragma once
// Restricted quadtree triangulation (RQT; Pajarola 1998, applied to depth maps in the
// depth-map triangulation work the method builds on): the image is covered by a quadtree of
// square blocks whose corners are pixels; a block is refined only where its vertices deviate
// from the coarser surface by more than a depth-dependent threshold, where it holds an invalid
// pixel or crosses the image border. Vertex dependencies keep neighbouring blocks within one
// level of each other, so the triangulation has no cracks and no T-junctions.

#include <vector>

#include "nodes/triangulate/pixel_grid.h"

namespace meshflow {

struct QuadtreeConfig {
  /// A vertex is needed when it lies farther than error_per_depth2 x depth^2 metres (depth =
  /// distance from the camera) from the surface of the coarser level: structured-light depth
  /// noise grows with depth^2 (0.002 /m: 2 mm at 1 m, 8 mm at 2 m).
  float error_per_depth2 = 0.002f;
  /// The threshold is raised to at least this many times the frame's own noise
  /// (estimate_noise_per_depth2), so that quantisation steps and noise of a real sensor do not
  /// refine the quadtree where the surface is flat; 0 = error_per_depth2 alone.
  float noise_multiple = 3.0f;
};

/// The threshold coefficient (1/m) the quadtree uses on `grid`: error_per_depth2, or
/// noise_multiple x the estimated noise when that is larger. O(pixels / 8).
float quadtree_threshold_per_depth2(const PointGrid& grid, const QuadtreeConfig& config);

/// Pixel-index triangles of the restricted quadtree over `grid` (valid pixels only; triangles
/// counter-clockwise seen from the camera). Unrefined blocks are split along their shorter 3D
/// diagonal; blocks with a needed centre are fans of up to 8 triangles; size-2 blocks that hold
/// an invalid pixel are triangulated per pixel quad. `keep` decides which triangles survive
/// (the occlusion test). `threshold_used`, when given, receives quadtree_threshold_per_depth2.
/// Deterministic; O(pixels).
std::vector<Triangle> restricted_quadtree_triangles(const PointGrid& grid,
                                                    const OcclusionTriangleTest& keep,
                                                    const QuadtreeConfig& config = {},
                                                    float* threshold_used = nullptr);

}  // namespace meshflow
