#pragma once
// Per-frame triangulation of depth maps (the depth-map triangulation work the method builds on):
// pre-processing removes invalid and out-of-range pixels and occlusion edges (depth jumps, with
// hysteresis so edges are continuous); then either the naive triangulation (two triangles per
// valid 2 x 2 pixel quad) or the restricted quadtree (large triangles where the surface is
// flat, pixel quads at borders and detail). Vertices are shared, one per used pixel; triangles
// whose viewing angle or shape marks them as spanning an occlusion are dropped.

#include <cstddef>

#include "nodes/decimate/qem_decimation.h"
#include "nodes/triangulate/pixel_grid.h"
#include "nodes/triangulate/restricted_quadtree.h"
#include "runtime/vertex_triangles.h"

namespace meshflow {

enum class DepthTriangulationMethod { kNaive, kRestrictedQuadtree };

struct DepthTriangulationConfig {
  DepthFilterConfig filter;  ///< range limits, smoothing, occlusion edges (hysteresis)
  DepthTriangulationMethod method = DepthTriangulationMethod::kNaive;
  QuadtreeConfig quadtree;  ///< kRestrictedQuadtree
  /// A triangle whose normal is more than this many degrees from the viewing ray is seen
  /// edge-on: it spans a depth jump, not a surface.
  float max_view_angle_deg = 84.0f;
  /// A triangle whose longest edge exceeds this many times its shortest is a sliver across a
  /// jump.
  float max_edge_ratio = 8.0f;
  /// Before decimation, as the clean step does (CleanupConfig): at vertices joining several fans
  /// of triangles (bow ties where two pixel quads meet at a corner across an occlusion edge),
  /// the smaller fans are removed (remove_smaller_fans: the mesh stays manifold, also for
  /// readers that weld vertices), ...
  bool repair_non_manifold_vertices = true;
  /// ... then connected components with fewer triangles: specks around occlusion edges and
  /// flying pixels (office1's RQT mesh had 241 edge-connected components, 217 of them under 20
  /// triangles). The clean step's rule and default (--min-component sets both); 0 = keep all.
  std::size_t min_component_triangles = 20;
  /// When in (0, 1): QEM decimation (qem_decimate, depth from the camera) down to this share
  /// of the triangles after triangulation; 0 = off.
  float decimate_to = 0.0f;
  /// Its other settings (target_ratio and viewpoint are set per frame). Per-frame meshes are
  /// made with frames in flight (the embedding API, sequences), which keep the cores busy: the
  /// walk's re-evaluations stay serial (walk_chunk = 0, the fewest evaluations).
  QemConfig decimation = [] {
    QemConfig q;
    q.walk_chunk = 0;
    return q;
  }();
};

struct TriangulationCounts {
  DepthFilterCounts filter;        ///< pre-processing
  std::size_t rejected_view = 0;   ///< naive: triangles dropped for their viewing angle
  std::size_t rejected_shape = 0;  ///< naive: triangles dropped for their edge ratio
  /// rqt: the threshold coefficient used (1/m; quadtree_threshold_per_depth2)
  float threshold_per_depth2 = 0.0f;
  FanRemovalCounts fans;  ///< remove_smaller_fans: non-manifold vertices and triangles removed
  /// Components of the triangulation (after the fans), and those removed
  /// (min_component_triangles).
  ComponentCounts components;
};

/// Triangulates a depth frame in the world frame (T_world_camera; metres). Triangles wind
/// counter-clockwise seen from the camera; vertices are the used pixels in row-major order;
/// smaller fans at non-manifold vertices and components smaller than
/// config.min_component_triangles are left out. No normals or colours
/// (the graph's triangulate stage adds normals, and colours from the frame's colour image).
/// Deterministic; O(pixels). Throws meshflow::Error for an empty or mis-sized image.
TriangleMesh triangulate_depth(const DepthFrame& frame, const DepthTriangulationConfig& config = {},
                               TriangulationCounts* counts = nullptr);

/// The same for an organized cloud (width x height points, NaN = invalid), e.g. a Kinect PCD
/// (see grid_from_organized); each vertex keeps its point's colour and normal where the cloud
/// has them. Throws meshflow::Error for an unorganized cloud.
TriangleMesh triangulate_organized(const PointCloud& cloud,
                                   const DepthTriangulationConfig& config = {},
                                   TriangulationCounts* counts = nullptr);

/// The pixel-index triangles of `grid` by config.method (before compaction into a mesh).
std::vector<Triangle> triangulate_grid(const PointGrid& grid,
                                       const DepthTriangulationConfig& config,
                                       TriangulationCounts* counts = nullptr);

}  // namespace meshflow
