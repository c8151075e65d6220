#pragma once
// The message that flows through the reconstruction graph (its configuration:
// graph/reconstruction_config.h).

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "nodes/close/close_surface.h"
#include "nodes/depth/depth_filter.h"
#include "nodes/extract/marching_cubes.h"
#include "nodes/filter/filter.h"
#include "nodes/fusion/integration_stats.h"
#include "nodes/normals/normals.h"
#include "nodes/optimize/optimize_mesh.h"
#include "nodes/triangulate/depth_triangulation.h"
#include "runtime/depth_frame.h"
#include "runtime/distance_field.h"
#include "runtime/point_cloud.h"
#include "runtime/sparse_grid.h"
#include "runtime/tracing.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {

class SpatialIndex;  // nodes/search/spatial_index.h

/// What a frame's input is, as "read" found it; it chooses the frame's route (stages::FrameRoutes).
enum class FrameKind {
  kCloud,       ///< a point cloud: the cloud route
  kDepthImage,  ///< a depth image, or an organized cloud read as one: the depth-image route
};

/// The depth-image route's part of a frame, set by "read" for a depth input.
struct DepthImagePart {
  /// The input. After "filter" its depth is the filtered depth in metres (F32), kept for the
  /// projective distance, which releases it; the colour waits for "extract" (vertex colours),
  /// which releases the rest.
  DepthFrame image;
  DepthFilterCounts counts;  ///< what the depth filter kept and dropped
};

/// A chunk's part of a frame: the out-of-core path (graph/chunked_reconstruction.h).
struct ChunkPart {
  /// "voxelize" keeps only these cells, the ones this chunk owns, so each cell's surface comes
  /// from one chunk.
  CellRange owned_cells;
  /// Chunks finished where they are meshed (graph/chunk_finish.h): the chunk edge in cells,
  /// whose seam vertices "optimize" holds fixed while it flips, trims the rim and runs the clean
  /// and holes steps on the chunk. 0: all of that waits for the stitched mesh.
  int finish_cells = 0;
  /// Per mesh vertex, whether it lies beyond the data as trim_rim judges
  /// (vertices_beyond_data); the rim is trimmed after stitching, where chunk cuts are no border.
  std::vector<std::uint8_t> beyond_data;
  /// With ExtractConfig::defer_feature_flips: per mesh vertex, 1 for extended marching cubes'
  /// feature vertices (their edge flips run once the chunks are stitched).
  std::vector<std::uint8_t> feature_vertices;
};

/// One input (a point cloud or a depth image) and everything the stages made of it. A frame that
/// fails a stage goes straight to the pipeline's end with `error` set, so ordering and
/// accounting stay exact. Three parts: the header every frame carries (identity, kind, outcome,
/// timings), the surface every route builds stage by stage, and each route's own part. Who
/// writes what (the routes: stages::FrameRoutes):
/// - the cloud route: cloud, origin, filter_counts, index, normals, then grid to optimize;
/// - the depth-image route: `depth` (DepthImagePart), then cloud (back-projected, normals from
///   the image) and grid to optimize, as a cloud's;
/// - a chunk of the out-of-core path: `chunk` (owned cells given, vertex flags made);
/// - per-frame triangulation: triangulation and mesh only; fusion: depth, integration;
/// - the compress stage on any route: compressed.
struct Frame {
  // The header.
  std::uint64_t seq = 0;             ///< gapless, assigned by the pipeline in input order
  std::string name;                  ///< where the input came from (a path, "synthetic", ...)
  std::size_t source_index = 0;      ///< position in the source sequence (seq counts fed frames)
  double timestamp_s = 0.0;          ///< capture time from the sequence, seconds
  double submitted_s = 0.0;          ///< monotonic_seconds() when it was handed in (its release)
  std::function<PointCloud()> load;  ///< produces a cloud input; called by the "read" stage
  std::function<DepthFrame()> load_depth;  ///< or a depth-image input (set one of the two)
  FrameKind kind = FrameKind::kCloud;      ///< set by "read"
  std::string error;                       ///< empty while the frame is healthy
  std::string failed_stage;
  std::vector<StageRecord> timings;  ///< one record per stage that ran
  /// Called (from the graph thread running it) as each stage begins, with the stage's name and,
  /// inside "optimize", each step's name (else nullptr): for progress lines. Optional.
  std::function<void(const char* stage, const char* step)> on_stage;

  // The surface, stage by stage, with what each stage reports.
  PointCloud cloud;  ///< after read: raw; after filter: filtered, with normals
  /// The input's PointCloud::origin (set by "read"): the mesh is in the same local frame;
  /// writers add it back (io::write_mesh).
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  FilterCounts filter_counts;
  /// Over cloud.positions (cloud route: "index"); released by "extract" (no later stage searches).
  std::shared_ptr<const SpatialIndex> index;
  NormalsReport normals;  ///< where the cloud's normals came from
  float voxel_size = 0.0f;
  /// After "extract" only its cells and corners (the cell corners are released: memory).
  SparseGrid grid;
  DistanceField distance;  ///< after "extract" only its valid flags and counts (values released)
  CloseReport closing;     ///< what the close stage did (closing.ran: it ran)
  ExtractMethod extract_method = ExtractMethod::kAuto;  ///< the method "extract" used
  std::size_t rim_trimmed = 0;  ///< triangles "extract" peeled off the rim (max_rim_voxels)
  TriangleMesh mesh;  ///< after extract: raw; after optimize: optimised (fusion: the map so far)
  /// After "extract" (not a chunk's): one byte per mesh vertex, 1 on the vertices extended
  /// marching cubes placed on sharp features, or, for planar marching cubes on clean samples,
  /// where the data shows one (data_feature_vertices), following them through the rim trim;
  /// empty for the other methods. "optimize" seeds its feature graph (and the holes step's
  /// lines) from them, then releases them (kept when it runs no step: the mesh is still the
  /// extraction).
  std::vector<std::uint8_t> feature_vertices;
  OptimizeReport optimize;  ///< what each optimisation step did
  /// With ReconstructionConfig::compression: the mesh as a compressed mesh file's bytes (.mfc,
  /// positions in world coordinates: origin added), for sending over a link.
  std::vector<unsigned char> compressed;

  // Each route's own part.
  std::optional<DepthImagePart> depth;  ///< the depth-image route's input (kind kDepthImage)
  std::optional<ChunkPart> chunk;       ///< a chunk of the out-of-core path
  /// Per-frame depth-map triangulation ("triangulate"): what its filter, occlusion tests and
  /// component filter dropped.
  TriangulationCounts triangulation;
  IntegrationStats integration;  ///< fusion: what integrating this frame did

  /// Whether every stage so far succeeded (error is empty).
  bool ok() const { return error.empty(); }
  /// Makes this a depth-image frame holding `image` (kind kDepthImage, `depth` set).
  void set_depth_image(DepthFrame image) {
    kind = FrameKind::kDepthImage;
    depth = DepthImagePart{std::move(image), DepthFilterCounts{}};
  }
};

using FramePtr = std::shared_ptr<Frame>;

}  // namespace meshflow
