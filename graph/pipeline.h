#pragma once
// The reconstruction pipeline as a oneTBB flow graph:
//
//   source -> limiter(K) -> read -> filter -> index -> normals -> voxelize -> distance -> extract
//          -> optimize -> sequencer -> sink --(decrement)--> limiter
//
// Stages are stateless, so several frames (clouds) are in flight at once (at most K), and
// each stage's kernel is itself parallel inside. The sink sees frames in input order.

#include <cstddef>
#include <functional>

#include "graph/frame.h"
#include "graph/reconstruction_config.h"

namespace meshflow {

/// A flow graph that frames pass through: what run_sequence() drives.
class FramePipeline {
 public:
  virtual ~FramePipeline() = default;
  /// Pulls frames from `next` until it returns nullptr, runs them through every stage and
  /// hands each finished frame (failed ones included, with `error` set) to `sink`, one at a
  /// time and in the order `next` produced them. Blocks until all frames are done.
  /// `next` and `sink` are called from graph threads, never concurrently with themselves.
  virtual void run(const std::function<FramePtr()>& next,
                   const std::function<void(const FramePtr&)>& sink) = 0;
};

class ReconstructionPipeline : public FramePipeline {
 public:
  /// `max_in_flight` (>= 1) bounds the frames inside the graph, and so memory. With
  /// `triangulate_depth_maps` the graph is source -> read -> triangulate -> sink instead: each
  /// depth map or organized cloud triangulated per frame (config.triangulation), no voxels.
  explicit ReconstructionPipeline(ReconstructionConfig config, std::size_t max_in_flight = 2,
                                  bool triangulate_depth_maps = false);

  void run(const std::function<FramePtr()>& next,
           const std::function<void(const FramePtr&)>& sink) override;

  /// Runs one frame (its `load` or `cloud` set, `on_stage` optional) through run() and returns
  /// it, failed or not.
  FramePtr run_frame(FramePtr frame);

  /// Reconstructs one in-memory cloud (convenience over run()).
  FramePtr reconstruct(PointCloud cloud, std::string name = "cloud");

  /// The configuration the pipeline was made with.
  const ReconstructionConfig& config() const { return config_; }

 private:
  ReconstructionConfig config_;
  std::size_t max_in_flight_;
  bool triangulate_depth_maps_;
};

}  // namespace meshflow
