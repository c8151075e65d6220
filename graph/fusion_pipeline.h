#pragma once
// Fusion of a posed depth sequence into one TSDF map, as a oneTBB flow graph:
//
//   source -> limiter(K) -> read -> filter -> sequencer -> integrate (serial, holds the map)
//          -> sink --(decrement)--> limiter
//
// Reading and filtering run for several frames at once; integration takes frames one at a time
// in input order (so the map does not depend on scheduling), each frame parallel inside.

#include <cstddef>
#include <functional>

#include "graph/pipeline.h"
#include "nodes/close/close_surface.h"
#include "nodes/fusion/tsdf_mesher.h"
#include "nodes/fusion/tsdf_volume.h"

namespace meshflow {

struct FusionConfig {
  /// depth_filter applies to every frame, optimize to the meshes; organized clouds that fit a
  /// pinhole camera (Kinect PCDs) are fused as their depth images, whatever organized_as_depth.
  ReconstructionConfig frames;
  TsdfConfig tsdf;
  /// > 0: after every N-th integrated frame, the frame carries the map's mesh so far (extracted
  /// incrementally) in Frame::mesh.
  std::size_t mesh_every = 0;
  /// Fuse the pixels along depth discontinuities too (frames.depth_filter's occlusion-edge
  /// removal off): they are an object's silhouette, which per-frame triangulation must not
  /// bridge but fusion needs (other views correct what they mix); on the Redwood frames at
  /// 1 cm removing them costs 5 % of the completeness.
  bool keep_occlusion_edges = true;
  /// Extraction treats voxels of at most this accumulated weight as unobserved (TsdfMesher).
  float min_weight = 0.0f;
};

class FusionPipeline : public FramePipeline {
 public:
  /// A pipeline fusing into a new empty map.
  FusionPipeline(const FusionConfig& config, std::size_t max_in_flight = 2);
  /// A pipeline that goes on fusing into `map` (e.g. read from a map file to resume a run) with
  /// config.tsdf's integration settings (the map keeps its own voxel size, truncation, weights
  /// and colour). Throws meshflow::Error when the map's voxel size differs from config.tsdf's.
  FusionPipeline(FusionConfig config, std::size_t max_in_flight, TsdfMap map);

  void run(const std::function<FramePtr()>& next,
           const std::function<void(const FramePtr&)>& sink) override;

  /// The map's surface (incremental marching cubes, then the configured optimisation steps);
  /// with `stats`, where the surface went (TsdfExtractStats, cells of the whole map). With
  /// config().frames.close.enabled (--close), the map's unseen parts are filled first
  /// (close_tsdf_map()) and the closed field is meshed by config().frames.extract's method
  /// (marching cubes for kAuto; no colours): a watertight surface; `stats` still describes the
  /// open map and closing() what the fill did. Intermediate meshes (mesh_every) stay open.
  TriangleMesh extract_mesh(TsdfExtractStats* stats = nullptr);
  /// What the last extract_mesh() with --close did (closing().ran: it closed the map).
  const CloseReport& closing() const { return closing_; }

  /// The TSDF map fused so far.
  const TsdfVolume& map() const { return map_; }
  /// Called in the integration node after each frame is integrated (frames in input order, one
  /// at a time, never during another integration) with the map, that frame's camera centre
  /// (world metres) and the frame (its seq and submitted_s: when it entered the graph): the one
  /// place a run may read the growing map, e.g. to send its changed blocks to viewers nearest
  /// the sensor first (serve/map_publisher.h). It must not keep the references, and whatever
  /// time it takes holds up the next integration. Set before run().
  void set_integration_observer(
      std::function<void(const TsdfMap& map, const Eigen::Vector3f& sensor, const Frame& frame)>
          observer) {
    observer_ = std::move(observer);
  }
  /// The configuration the pipeline was made with.
  const FusionConfig& config() const { return config_; }

 private:
  std::uint64_t integrate(Frame& f);

  FusionConfig config_;
  std::size_t max_in_flight_;
  TsdfVolume map_;
  TsdfMesher mesher_;
  std::size_t integrated_ = 0;
  CloseReport closing_;
  Eigen::Vector3f last_sensor_ = Eigen::Vector3f::Zero();  // the integrated frame's camera
  std::function<void(const TsdfMap&, const Eigen::Vector3f&, const Frame&)> observer_;
};

}  // namespace meshflow
