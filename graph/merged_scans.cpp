#include "graph/merged_scans.h"

#include <oneapi/tbb/flow_graph.h>

#include <algorithm>
#include <vector>

#include "graph/frame_graph.h"

namespace meshflow {

namespace flow = tbb::flow;

ScanPreparationPipeline::ScanPreparationPipeline(ReconstructionConfig config,
                                                 std::size_t max_in_flight)
    : config_(std::move(config)), max_in_flight_(std::max<std::size_t>(1, max_in_flight)) {}

void ScanPreparationPipeline::run(const std::function<FramePtr()>& next,
                                  const std::function<void(const FramePtr&)>& sink) {
  const std::vector<stages::NamedStage> preparation(std::begin(stages::kPointCloudStages),
                                                    std::begin(stages::kPointCloudStages) + 4);
  flow::graph g;
  detail::FrameGraphEnds ends(g, max_in_flight_, next, sink);
  detail::StageChain chain(g, preparation, config_);
  flow::sequencer_node<FramePtr> in_order(g, [](const FramePtr& f) { return f->seq; });
  flow::make_edge(ends.entry(), chain.front());
  flow::make_edge(chain.back(), in_order);
  flow::make_edge(in_order, ends.exit());
  ends.run(g);
}

void append_scan(PointCloud& into, const PointCloud& scan) {
  const bool colors = scan.has_colors() && (into.positions.empty() || into.has_colors());
  into.positions.insert(into.positions.end(), scan.positions.begin(), scan.positions.end());
  into.normals.insert(into.normals.end(), scan.normals.begin(), scan.normals.end());
  if (colors)
    into.colors.insert(into.colors.end(), scan.colors.begin(), scan.colors.end());
  else
    into.colors.clear();
  into.intensities.clear();
  into.width = into.height = 0;  // unorganized
  into.has_sensor_origin = false;
}

ReconstructionConfig merged_pass_config(const ReconstructionConfig& config) {
  ReconstructionConfig c = config;
  c.filter = FilterConfig{};
  c.normals.source = NormalSource::kInput;
  c.organized_as_depth = false;
  return c;
}

}  // namespace meshflow
