#pragma once
// Stage bodies: each calls one kernel on a Frame and returns the number of work items it
// processed. They know nothing of the flow graph, so they can be tested and timed alone.

#include <cstdint>
#include <functional>
#include <vector>

#include "graph/frame.h"
#include "graph/reconstruction_config.h"

namespace meshflow::stages {

/// Loads the frame; an organized cloud that fits a pinhole camera becomes its depth image
/// (c.organized_as_depth, depth_frame_from_organized()).
std::uint64_t read(Frame& f, const ReconstructionConfig& c);  ///< points / pixels read
/// A point cloud's filter (c.filter); fails a cloud left with fewer than 3 points, or whose
/// points coincide or lie on a line.
std::uint64_t filter(Frame& f, const ReconstructionConfig& c);  ///< points kept
/// A depth frame's filter: the depth filter (c.depth_filter), then the back-projection to an
/// organized cloud with normals from image neighbours and c.filter on it (f.depth: DepthImagePart);
/// keeps the filtered metric depth and the colour for "distance" and "extract". Depth frames
/// take no "index" or "normals" stage.
std::uint64_t depth_to_cloud(Frame& f, const ReconstructionConfig& c);  ///< points kept
/// Puts an unorganized cloud in Morton order (in_morton_order()) and builds the kd-tree.
std::uint64_t index(Frame& f, const ReconstructionConfig& c);     ///< points indexed (kd-tree)
std::uint64_t normals(Frame& f, const ReconstructionConfig& c);   ///< normals estimated
std::uint64_t voxelize(Frame& f, const ReconstructionConfig& c);  ///< cells
/// A point cloud's signed distance: Hoppe's, to the tangent plane of the nearest point.
std::uint64_t distance(Frame& f, const ReconstructionConfig& c);  ///< corners evaluated
/// A depth frame's signed distance: projective, along the camera's rays (c.projective); then
/// releases the depth image.
std::uint64_t depth_distance(Frame& f, const ReconstructionConfig& c);  ///< corners evaluated
/// --close (c.close): fills the distance of the corners without data by volumetric diffusion
/// and adds the cells the closed surface crosses (close_distance_field(), f.closing). Fails a
/// chunk (f.chunk set): closing needs the whole cloud.
std::uint64_t close(Frame& f, const ReconstructionConfig& c);  ///< corners filled
/// Fails a frame left without triangles (nothing extracted, or the rim trim took them all),
/// saying why, so no path passes on an "ok" frame with an empty mesh; a chunk (f.chunk
/// set) may be empty.
std::uint64_t extract(Frame& f, const ReconstructionConfig& c);  ///< triangles
/// Fails a frame (not a chunk) whose steps removed every triangle, naming the step.
std::uint64_t optimize(Frame& f, const ReconstructionConfig& c);  ///< triangles kept

/// Fusion's filter: the depth filter only (no back-projection); keeps the frame's colour.
/// Fails frames that are not depth images.
std::uint64_t filter_depth_image(Frame& f, const ReconstructionConfig& c);  ///< valid pixels

/// Depth-map triangulation straight into `mesh` (c.triangulation; no voxel grid) of a depth
/// frame, or of an organized point cloud (width x height points, NaN = invalid, e.g. a Kinect
/// PCD) seen from its sensor origin. Fails other frames, naming what was expected, and frames
/// that give no triangle.
std::uint64_t triangulate(Frame& f, const ReconstructionConfig& c);  ///< triangles

/// Codes the frame's mesh into f.compressed (c.compression, c.compress; the frame's origin
/// added). A frame without triangles gets a file of its vertices.
std::uint64_t compress(Frame& f, const ReconstructionConfig& c);  ///< bytes written

using StageFunction = std::uint64_t (*)(Frame&, const ReconstructionConfig&);

struct NamedStage {
  const char* name;
  StageFunction body;
};

/// The point-cloud stages in pipeline order: read, filter, index, normals, voxelize, distance,
/// extract, optimize.
extern const NamedStage kPointCloudStages[8];
/// The depth-image stages in pipeline order: read, filter (depth_to_cloud), voxelize, distance
/// (depth_distance), extract, optimize.
extern const NamedStage kDepthImageStages[6];
/// The per-frame depth-map path: read, triangulate.
extern const NamedStage kDepthTriangulationStages[2];

/// The stages a frame takes through a frame pipeline: `first` on every frame (it reads the
/// input, and so decides whether the frame is a point cloud or a depth image), then the `cloud`
/// or the `depth` route (an empty route goes straight to the end). Wired by
/// detail::StageRoutes.
struct FrameRoutes {
  NamedStage first;
  std::vector<NamedStage> cloud;
  std::vector<NamedStage> depth;
};

/// The routes a frame pipeline wires: "read", then "triangulate" for both kinds when
/// `triangulate_depth_maps`; else kPointCloudStages' and kDepthImageStages' stages after "read",
/// with "close" before "extract" when `close_surfaces`; then "compress" on both routes unless
/// `compression` is kNone.
FrameRoutes frame_routes(bool triangulate_depth_maps,
                         MeshCompression compression = MeshCompression::kNone,
                         bool close_surfaces = false);

/// Runs `body` on `f` unless the frame already failed, appending a StageRecord; a thrown
/// exception becomes the frame's error. Thread-safe for distinct frames.
void run_stage(const char* name, StageFunction body, Frame& f, const ReconstructionConfig& c);

/// The same for a stage with state of its own (e.g. fusion into a map): `body` returns the
/// number of work items.
void run_stage(const char* name, const std::function<std::uint64_t(Frame&)>& body, Frame& f);

}  // namespace meshflow::stages
