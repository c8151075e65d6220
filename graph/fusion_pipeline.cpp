#include "graph/fusion_pipeline.h"

#include <oneapi/tbb/flow_graph.h>

#include <algorithm>
#include <utility>

#include "graph/close_tsdf_map.h"
#include "graph/frame_graph.h"
#include "nodes/extract/extract_surface.h"
#include "runtime/error.h"

namespace meshflow {
namespace flow = tbb::flow;

namespace {

// `map`, when its voxel size is the run's (`tsdf`); throws naming both otherwise.
TsdfMap map_of_the_run(TsdfMap map, const TsdfConfig& tsdf) {
  if (map.config().voxel_size != tsdf.voxel_size) {
    throw Error("fusion", "voxel size",
                "the map has " + std::to_string(map.config().voxel_size) + " m voxels, the run " +
                    std::to_string(tsdf.voxel_size) + " m");
  }
  return map;
}

}  // namespace

FusionPipeline::FusionPipeline(const FusionConfig& config, std::size_t max_in_flight)
    : FusionPipeline(config, max_in_flight, TsdfMap(config.tsdf)) {}

FusionPipeline::FusionPipeline(FusionConfig config, std::size_t max_in_flight, TsdfMap map)
    : config_(std::move(config)),
      max_in_flight_(std::max<std::size_t>(1, max_in_flight)),
      map_(map_of_the_run(std::move(map), config_.tsdf), config_.tsdf),
      mesher_(config_.min_weight) {
  config_.frames.organized_as_depth = true;  // fusion integrates depth images only
  if (config_.keep_occlusion_edges) config_.frames.depth_filter.edge_high = 0.0f;
}

std::uint64_t FusionPipeline::integrate(Frame& f) {
  f.integration = map_.integrate(f.depth->image);
  last_sensor_ = f.depth->image.T_world_camera.translation();
  f.depth->image = DepthFrame{};  // the filter's counts stay for the report
  ++integrated_;
  return f.integration.voxels_updated;
}

void FusionPipeline::run(const std::function<FramePtr()>& next,
                         const std::function<void(const FramePtr&)>& sink) {
  using detail::StageNode;
  using detail::StageNodeBody;
  const ReconstructionConfig& c = config_.frames;
  flow::graph g;
  detail::FrameGraphEnds ends(g, max_in_flight_, next, sink);
  StageNode read(g, flow::unlimited, StageNodeBody("read", stages::read, c));
  StageNode filter(g, flow::unlimited, StageNodeBody("filter", stages::filter_depth_image, c));
  // Integration and delivery each take the frames in input order from a sequencer.
  const auto by_seq = [](const FramePtr& f) { return f->seq; };
  flow::sequencer_node<FramePtr> in_order(g, by_seq), integrated_in_order(g, by_seq);
  detail::InOrderNode<FramePtr> integrate(g, flow::serial, [&](const FramePtr& f) {
    stages::run_stage(
        "integrate", [this](Frame& frame) { return this->integrate(frame); }, *f);
    if (f->ok() && observer_)  // (a viewer's: its time and failure are the frame's)
      stages::run_stage(
          "publish",
          [this](Frame& frame) {
            observer_(map_, last_sensor_, frame);
            return std::uint64_t{0};
          },
          *f);
    if (f->ok() && config_.mesh_every > 0 && integrated_ % config_.mesh_every == 0) {
      stages::run_stage(
          "extract",
          [this](Frame& frame) {
            frame.mesh = extract_mesh();
            return static_cast<std::uint64_t>(frame.mesh.triangles.size());
          },
          *f);
    }
    return f;
  });
  flow::make_edge(ends.entry(), read);
  flow::make_edge(read, filter);
  flow::make_edge(filter, in_order);
  flow::make_edge(in_order, integrate);
  flow::make_edge(integrate, integrated_in_order);
  flow::make_edge(integrated_in_order, ends.exit());
  ends.run(g);
}

TriangleMesh FusionPipeline::extract_mesh(TsdfExtractStats* stats) {
  const OptimizeConfig optimize =
      optimize_config_for_voxel(config_.frames, config_.tsdf.voxel_size);
  if (!config_.frames.close.enabled) return optimize_mesh(mesher_.extract(map_, stats), optimize);
  if (stats != nullptr) mesher_.update(map_, stats);  // the open map's cell counts
  const ClosedDistance closed =
      close_tsdf_map(map_, config_.min_weight, config_.frames.close, &closing_);
  ExtractConfig extract = config_.frames.extract;
  // A map has no points for the methods that read them (planar, extended marching cubes).
  if (extract.method == ExtractMethod::kAuto) extract.method = ExtractMethod::kMarchingCubes;
  TriangleMesh mesh = extract_surface(closed.grid, closed.distance, PointCloud{}, nullptr, extract);
  // The open mesher blends the map's colours along each edge; the closed grid has none: the
  // nearest observed surface voxels' colours (the filled parts take the nearest seen colour).
  mesh.colors = tsdf_map_vertex_colors(map_, config_.min_weight, mesh.vertices);
  return optimize_mesh(mesh, optimize);
}

}  // namespace meshflow
