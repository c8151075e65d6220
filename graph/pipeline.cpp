#include "graph/pipeline.h"

#include <algorithm>

#include "graph/frame_graph.h"

namespace meshflow {
ReconstructionPipeline::ReconstructionPipeline(ReconstructionConfig config,
                                               std::size_t max_in_flight,
                                               bool triangulate_depth_maps)
    : config_(std::move(config)),
      max_in_flight_(std::max<std::size_t>(1, max_in_flight)),
      triangulate_depth_maps_(triangulate_depth_maps) {}

void ReconstructionPipeline::run(const std::function<FramePtr()>& next,
                                 const std::function<void(const FramePtr&)>& sink) {
  detail::run_stage_routes(
      max_in_flight_,
      stages::frame_routes(triangulate_depth_maps_, config_.compression, config_.close.enabled),
      config_, next, sink);
}

FramePtr ReconstructionPipeline::run_frame(FramePtr frame) {
  bool given = false;
  run([&]() -> FramePtr { return given ? nullptr : (given = true, frame); },
      [](const FramePtr&) {});
  return frame;
}

FramePtr ReconstructionPipeline::reconstruct(PointCloud cloud, std::string name) {
  auto frame = std::make_shared<Frame>();
  frame->name = std::move(name);
  frame->cloud = std::move(cloud);
  return run_frame(std::move(frame));
}

}  // namespace meshflow
