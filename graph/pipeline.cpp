#include "graph/pipeline.h"

#include <oneapi/tbb/flow_graph.h>

#include <algorithm>

#include "graph/frame_graph.h"

namespace meshflow {
namespace flow = tbb::flow;

ReconstructionPipeline::ReconstructionPipeline(ReconstructionConfig config,
                                               std::size_t max_in_flight,
                                               bool triangulate_depth_maps)
    : config_(std::move(config)),
      max_in_flight_(std::max<std::size_t>(1, max_in_flight)),
      triangulate_depth_maps_(triangulate_depth_maps) {}

void ReconstructionPipeline::run(const std::function<FramePtr()>& next,
                                 const std::function<void(const FramePtr&)>& sink) {
  flow::graph g;
  detail::FrameGraphEnds ends(g, max_in_flight_, next, sink);
  detail::StageChain chain(g, triangulate_depth_maps_, config_);
  flow::sequencer_node<FramePtr> in_order(g, [](const FramePtr& f) { return f->seq; });

  flow::make_edge(ends.entry(), chain.front());
  flow::make_edge(chain.back(), in_order);
  flow::make_edge(in_order, ends.exit());
  ends.run(g);
}

FramePtr ReconstructionPipeline::reconstruct(PointCloud cloud, std::string name) {
  auto frame = std::make_shared<Frame>();
  frame->name = std::move(name);
  frame->cloud = std::move(cloud);
  bool given = false;
  FramePtr result;
  run(
      [&]() -> FramePtr {
        if (given) return nullptr;
        given = true;
        return frame;
      },
      [&](const FramePtr& f) { result = f; });
  return result;
}

}  // namespace meshflow
