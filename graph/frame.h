#pragma once
// The message that flows through the reconstruction graph, and the pipeline's configuration.

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "nodes/close/close_surface.h"
#include "nodes/compress/compressed_mesh.h"
#include "nodes/depth/depth_filter.h"
#include "nodes/distance/hoppe_distance.h"
#include "nodes/distance/projective_distance.h"
#include "nodes/extract/marching_cubes.h"
#include "nodes/filter/filter.h"
#include "nodes/fusion/tsdf_volume.h"
#include "nodes/normals/normals.h"
#include "nodes/optimize/optimize_mesh.h"
#include "nodes/search/spatial_index.h"
#include "nodes/triangulate/depth_triangulation.h"
#include "nodes/voxelize/voxelize.h"
#include "runtime/depth_frame.h"
#include "runtime/point_cloud.h"
#include "runtime/tracing.h"
#include "runtime/triangle_mesh.h"

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

/// One input (a point cloud) and everything the stages made of it. A frame that fails a stage
/// keeps flowing with `error` set, so ordering and accounting stay exact.
struct Frame {
  std::uint64_t seq = 0;             ///< gapless, assigned by the pipeline in input order
  std::string name;                  ///< where the input came from (a path, "synthetic", ...)
  std::size_t source_index = 0;      ///< position in the source sequence (seq counts fed frames)
  double timestamp_s = 0.0;          ///< capture time from the sequence, seconds
  double submitted_s = 0.0;          ///< monotonic_seconds() when it was handed in (live API)
  std::function<PointCloud()> load;  ///< produces a cloud input; called by the "read" stage
  std::function<DepthFrame()> load_depth;  ///< or a depth-image input (set one of the two)

  /// The depth input; after "filter" its image is the filtered depth in metres (F32), kept
  /// for the projective distance and released by "distance".
  std::shared_ptr<DepthFrame> depth;
  DepthFilterCounts depth_counts;
  bool normals_from_image = false;  ///< normals came from image neighbours (depth input)
  NormalsReport normals;            ///< where the cloud's normals came from (cloud path)

  PointCloud cloud;  ///< after read: raw; after filter: filtered, with normals
  /// The input's PointCloud::origin (set by "read"): the mesh is in the same local frame;
  /// writers add it back (io::write_mesh).
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  FilterCounts filter_counts;
  std::shared_ptr<const SpatialIndex> index;  ///< over cloud.positions, built by "index"
  float voxel_size = 0.0f;
  /// Chunked (out-of-core) reconstruction: "voxelize" keeps only these cells, the ones this
  /// chunk owns, so each cell's surface comes from one chunk (graph/chunked_reconstruction.h).
  std::optional<CellRange> owned_cells;
  SparseGrid grid;
  DistanceField distance;
  CloseReport closing;  ///< what the close stage did (closing.ran: it ran)
  ExtractMethod extract_method = ExtractMethod::kAuto;  ///< the method "extract" used
  std::size_t rim_trimmed = 0;  ///< triangles "extract" peeled off the rim (max_rim_voxels)
  /// Chunks (owned_cells set): per mesh vertex, whether it lies beyond the data as trim_rim
  /// judges (vertices_beyond_data); the rim is trimmed after stitching, where chunk cuts are
  /// no border.
  std::vector<std::uint8_t> beyond_data;
  /// Chunks with ExtractConfig::defer_feature_flips: per mesh vertex, 1 for extended marching
  /// cubes' feature vertices (their edge flips run once the chunks are stitched).
  std::vector<std::uint8_t> feature_vertices;
  /// Per-frame depth-map triangulation ("triangulate"): what its filter, occlusion tests and
  /// component filter dropped.
  TriangulationCounts triangulation;
  TriangleMesh mesh;  ///< after extract: raw; after optimize: optimised (fusion: the map so far)
  OptimizeReport optimize;       ///< what each optimisation step did
  IntegrationStats integration;  ///< fusion: what integrating this frame did
  /// With ReconstructionConfig::compression: the mesh as a compressed mesh file's bytes (.mfc,
  /// positions in world coordinates: origin added), for sending over a link.
  std::vector<unsigned char> compressed;

  std::string error;  ///< empty while the frame is healthy
  std::string failed_stage;
  std::vector<StageRecord> timings;  ///< one record per stage that ran
  /// Called (from the graph thread running it) as each stage begins, with the stage's name and,
  /// inside "optimize", each step's name (else nullptr): for progress lines. Optional.
  std::function<void(const char* stage, const char* step)> on_stage;

  /// Whether every stage so far succeeded (error is empty).
  bool ok() const { return error.empty(); }
};

using FramePtr = std::shared_ptr<Frame>;

}  // namespace meshflow
