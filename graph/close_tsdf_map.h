#pragma once
// The close stage on a fused TSDF map (run --fuse --close): the map's observed voxels are the
// data the close stage holds; its unseen parts (an object's underside, the inside of a closed
// shape) are filled by the same diffusion as a merged cloud's distance field. In graph/: it
// joins two stages' kernels (nodes/fusion, nodes/close), which nodes/ may not.

#include <Eigen/Core>
#include <vector>

#include "nodes/close/close_surface.h"
#include "nodes/fusion/tsdf_map.h"
#include "runtime/rgb8.h"

namespace meshflow {

/// The voxels of `map` whose accumulated weight is above `min_weight` (TsdfMesher's observed
/// voxels), as a grid and distance field: voxel (i, j, k) is corner (i, j, k), at (i, j, k) x
/// the map's voxel size; `distance` holds their fused distances (metres, positive in front of
/// the surface, clipped to the truncation), all valid; the grid has no cells. Parallel over
/// blocks, deterministic; not thread-safe against integrate() on the map. O(voxels log voxels).
ClosedDistance tsdf_map_distances(const TsdfMap& map, float min_weight);

/// The map's closed surface: close_distance_field() over tsdf_map_distances(). The observed
/// voxels keep their distances; the map's free space (voxels fused at +truncation, carved ones)
/// is observed and so held outside, as a line of sight holds a cloud's seen-empty corners. The
/// grid holds the cells the closed zero set crosses, with a value at each of their corners;
/// marching cubes over it give a watertight surface. Same cost and threading as
/// close_distance_field() after O(voxels log voxels) to gather the map's voxels.
ClosedDistance close_tsdf_map(const TsdfMap& map, float min_weight, const CloseConfig& config,
                              CloseReport* report = nullptr);

/// Colours for the `vertices` (metres, the map's frame) of a mesh of the map's closed surface:
/// each the inverse-distance blend of the colours of its 4 nearest surface voxels (weight above
/// `min_weight`, fused distance within one voxel of zero, at their centres), so an observed part
/// takes the colours the open mesh would and a filled part those of the nearest observed
/// surface. Empty when the map has no surface voxel. Parallel, deterministic; not thread-safe
/// against integrate() on the map. O((S + V) log S) for S surface voxels and V vertices.
std::vector<Rgb8> tsdf_map_vertex_colors(const TsdfMap& map, float min_weight,
                                         const std::vector<Eigen::Vector3f>& vertices);

}  // namespace meshflow
