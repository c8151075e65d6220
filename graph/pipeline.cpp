#include "graph/pipeline.h"

#include <oneapi/tbb/flow_graph.h>

#include <algorithm>

#include "graph/frame_graph.h"

namespace meshflow {
namespace flow = tbb::flow;

using detail::StageNode;
using detail::StageNodeBody;

ReconstructionPipeline::ReconstructionPipeline(ReconstructionConfig config,
                                               std::size_t max_in_flight)
    : config_(std::move(config)), max_in_flight_(std::max<std::size_t>(1, max_in_flight)) {}

void ReconstructionPipeline::run(const std::function<FramePtr()>& next,
                                 const std::function<void(const FramePtr&)>& sink) {
  flow::graph g;
  detail::FrameGraphEnds ends(g, max_in_flight_, next, sink);
  StageNode read(g, flow::unlimited, StageNodeBody("read", stages::read, config_));
  StageNode filter(g, flow::unlimited, StageNodeBody("filter", stages::filter, config_));
  StageNode index(g, flow::unlimited, StageNodeBody("index", stages::index, config_));
  StageNode normals(g, flow::unlimited, StageNodeBody("normals", stages::normals, config_));
  StageNode voxelize(g, flow::unlimited, StageNodeBody("voxelize", stages::voxelize, config_));
  StageNode distance(g, flow::unlimited, StageNodeBody("distance", stages::distance, config_));
  StageNode extract(g, flow::unlimited, StageNodeBody("extract", stages::extract, config_));
  StageNode optimize(g, flow::unlimited, StageNodeBody("optimize", stages::optimize, config_));
  flow::sequencer_node<FramePtr> in_order(g, [](const FramePtr& f) { return f->seq; });

  flow::make_edge(ends.entry(), read);
  flow::make_edge(read, filter);
  flow::make_edge(filter, index);
  flow::make_edge(index, normals);
  flow::make_edge(normals, voxelize);
  flow::make_edge(voxelize, distance);
  flow::make_edge(distance, extract);
  flow::make_edge(extract, optimize);
  flow::make_edge(optimize, in_order);
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
