#pragma once
// The configuration of every stage of a frame pipeline (ReconstructionConfig) and the settings
// derived from it per frame.

#include <cstddef>

#include "nodes/close/close_surface.h"
#include "nodes/compress/compressed_mesh.h"
#include "nodes/depth/depth_filter.h"
#include "nodes/distance/hoppe_distance.h"
#include "nodes/distance/projective_distance.h"
#include "nodes/extract/marching_cubes.h"
#include "nodes/filter/filter.h"
#include "nodes/normals/normals.h"
#include "nodes/optimize/optimize_mesh.h"
#include "nodes/triangulate/depth_triangulation.h"
#include "nodes/voxelize/voxelize.h"
#include "runtime/point_cloud.h"
#include "runtime/sparse_grid.h"

namespace meshflow {

/// Whether and how the pipeline's last stage compresses each frame's mesh (Frame::compressed).
enum class MeshCompression { kNone, kEdgebreaker, kProgressive };

/// Configuration of every stage; defaults are the thesis's published ones.
/// voxelize.voxel_size <= 0 means "choose from the point spacing" (auto_voxel_size).
struct ReconstructionConfig {
  DepthFilterConfig depth_filter;  ///< depth-image inputs only
  FilterConfig filter;
  NormalsConfig normals;
  /// Voxel size 0 (the default, as in the CLI): chosen per frame, 3x the median point spacing
  /// of a cloud (auto_voxel_size, before the outlier clusters are removed) or from the depth
  /// and focal length of a depth frame.
  VoxelizeConfig voxelize = VoxelizeConfig{0.0f};
  /// voxelize.voxel_size was chosen by meshflow from the whole input (the out-of-core path's
  /// statistics pass), not given: the outlier clusters are then linked at exactly that voxel,
  /// as one process links them at its own automatic choice.
  bool voxel_from_whole_input = false;
  DistanceConfig distance;              ///< clouds (Hoppe)
  CloseConfig close;                    ///< --close: the close stage (off by default)
  ProjectiveDistanceConfig projective;  ///< depth frames
  ExtractConfig extract;
  OptimizeConfig optimize;                 ///< steps (default: clean, holes) and their settings
  DepthTriangulationConfig triangulation;  ///< the per-frame depth-map path (LivePipeline)
  /// An organized cloud that is a pinhole back-projection (depth_frame_from_organized(): Kinect /
  /// OpenNI PCD frames) is read as its depth image and takes the depth path: image normals and
  /// projective distance, about 4x faster per frame but single-view (surfaces seen at grazing
  /// angles drop out). Off: the cloud path (kNN normals, Hoppe distance). Fusion always reads
  /// such clouds as depth images.
  bool organized_as_depth = false;
  /// The planes, sharpen and retriangulate steps take a region as planar only when the 95th
  /// percentile of its vertices' distances to its plane is within this many voxels
  /// (PlanarRegionConfig::max_deviation, set per frame from its voxel size unless given).
  /// 0 = no check.
  float plane_tolerance_voxels = 0.25f;
  /// Clouds: border triangles farther than this many voxels from the nearest point are peeled
  /// off after extraction (trim_rim), so an open scan's rim stays within it of the data. 0 = off.
  float max_rim_voxels = 1.0f;
  /// The retriangulate step's Douglas-Peucker tolerance in voxels (0.4: 2 cm at 5 cm voxels);
  /// 0 = use optimize.retriangulation.contour_tolerance (metres) as it is.
  float contour_tolerance_voxels = 0.4f;
  /// The voxelize stage fails the frame when its points, grid and the distance field to come
  /// would hold more than this many bytes (0 = no limit): a voxel far too small for the input
  /// gives an error naming the input and the limit before the distance and extract stages
  /// allocate, not an out-of-memory kill. See frame_memory_estimate().
  std::size_t max_memory_bytes = 0;
  /// A "compress" stage after the last one codes each frame's mesh into Frame::compressed (a
  /// .mfc image in world coordinates; nodes/compress) with `compress`'s settings.
  MeshCompression compression = MeshCompression::kNone;
  compress::CompressConfig compress;
};

/// Bytes a cloud frame holds once its grid and distance field exist: the points with their
/// normals, colours and intensities, the grid's cell and corner keys, the cells' corner indices
/// and one distance and validity flag per corner. O(1).
std::size_t frame_memory_estimate(const PointCloud& cloud, const SparseGrid& grid);

/// c.optimize with the settings that depend on the frame's voxel size (metres) filled in.
OptimizeConfig optimize_config_for_voxel(const ReconstructionConfig& c, float voxel_size);

}  // namespace meshflow
