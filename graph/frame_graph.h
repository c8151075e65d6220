#pragma once
// Flow-graph parts every frame pipeline shares (internal to graph/): the numbered source feeding
// a limiter of K frames in flight, the serial delivery to the sink that releases the limiter,
// the node body that runs one stateless stage, and the routes that send each frame only
// through the stages of its kind.

#include <oneapi/tbb/flow_graph.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <memory>
#include <tuple>
#include <vector>

#include "graph/frame.h"
#include "graph/stages.h"

namespace meshflow::detail {

/// A flow-graph body that runs one stage on the frame it is given and passes the frame on.
class StageNodeBody {
 public:
  StageNodeBody(const char* name, stages::StageFunction fn, const ReconstructionConfig& config)
      : name_(name), fn_(fn), config_(&config) {}
  FramePtr operator()(const FramePtr& frame) const {
    stages::run_stage(name_, fn_, *frame, *config_);
    return frame;
  }

 private:
  const char* name_;
  stages::StageFunction fn_;
  const ReconstructionConfig* config_;
};

using StageNode = tbb::flow::function_node<FramePtr, FramePtr>;

/// A flow-graph node that runs one stage and routes the frame by what the stage left: port 0
/// takes a healthy frame to the next stage (after the routing stage: a point cloud), port 1 a
/// healthy depth frame after the routing stage, port 2 a failed frame straight to the end.
using RoutedStageNode =
    tbb::flow::multifunction_node<FramePtr, std::tuple<FramePtr, FramePtr, FramePtr>>;

/// The body of a RoutedStageNode. `routes_by_kind`: the stage that decides a frame's kind (it
/// reads the input) sends depth frames to port 1.
class RoutedStageBody {
 public:
  RoutedStageBody(const char* name, stages::StageFunction fn, const ReconstructionConfig& config,
                  bool routes_by_kind)
      : name_(name), fn_(fn), config_(&config), routes_by_kind_(routes_by_kind) {}
  void operator()(const FramePtr& frame, RoutedStageNode::output_ports_type& ports) const {
    stages::run_stage(name_, fn_, *frame, *config_);
    if (!frame->ok())
      std::get<2>(ports).try_put(frame);
    else if (routes_by_kind_ && frame->kind == FrameKind::kDepthImage)
      std::get<1>(ports).try_put(frame);
    else
      std::get<0>(ports).try_put(frame);
  }

 private:
  const char* name_;
  stages::StageFunction fn_;
  const ReconstructionConfig* config_;
  bool routes_by_kind_;
};

/// The stages of a stages::FrameRoutes as flow-graph nodes, one unlimited node per stage (frames
/// overlap in every stage): the first stage for every frame, then the cloud route or the depth
/// route by the frame's kind, every route's end and every failed frame into `end` (a sequencer
/// on Frame::seq). A frame visits only the stages of its own route, and none after it failed.
/// The caller puts frames into entry(); `config` and `end` must outlive the graph.
class StageRoutes {
 public:
  StageRoutes(tbb::flow::graph& g, const stages::FrameRoutes& routes,
              const ReconstructionConfig& config, tbb::flow::receiver<FramePtr>& end)
      : first_(g, tbb::flow::unlimited,
               RoutedStageBody(routes.first.name, routes.first.body, config, true)) {
    tbb::flow::make_edge(tbb::flow::output_port<2>(first_), end);
    chain(g, tbb::flow::output_port<0>(first_), routes.cloud, config, end);
    chain(g, tbb::flow::output_port<1>(first_), routes.depth, config, end);
  }
  RoutedStageNode& entry() { return first_; }

 private:
  // Wires `route` one stage after the other behind `from`, the last one (or `from` itself when
  // the route is empty) into `end`, and each stage's failed frames into `end`.
  void chain(tbb::flow::graph& g, tbb::flow::sender<FramePtr>& from,
             const std::vector<stages::NamedStage>& route, const ReconstructionConfig& config,
             tbb::flow::receiver<FramePtr>& end) {
    tbb::flow::sender<FramePtr>* previous = &from;
    for (const stages::NamedStage& stage : route) {
      nodes_.push_back(std::make_unique<RoutedStageNode>(
          g, tbb::flow::unlimited, RoutedStageBody(stage.name, stage.body, config, false)));
      tbb::flow::make_edge(*previous, *nodes_.back());
      tbb::flow::make_edge(tbb::flow::output_port<2>(*nodes_.back()), end);
      previous = &tbb::flow::output_port<0>(*nodes_.back());
    }
    tbb::flow::make_edge(*previous, end);
  }

  RoutedStageNode first_;
  std::vector<std::unique_ptr<RoutedStageNode>> nodes_;
};

/// A serial node that takes frames one at a time in the order its predecessor, a buffering node
/// (a sequencer), hands them out. A serial node that queues (tbb::flow::queueing) keeps no
/// order across threads: a message put from another thread just as it finishes one can run
/// before the ones waiting in its queue. One that rejects while busy pulls the next message from
/// its predecessor when it is free, so a sequencer in front decides the order alone.
template <typename Output>
using InOrderNode = tbb::flow::function_node<FramePtr, Output, tbb::flow::rejecting>;

/// source -> limiter(K) ... deliver(sink) --(decrement)--> limiter. The source numbers frames
/// (Frame::seq) in the order `next` returns them; connect the first stage to entry() and a
/// sequencer on Frame::seq at the end of the stages to exit() (which delivers in its order: see
/// InOrderNode). `next` and `sink` must outlive run().
class FrameGraphEnds {
 public:
  FrameGraphEnds(tbb::flow::graph& g, std::size_t max_in_flight,
                 const std::function<FramePtr()>& next,
                 const std::function<void(const FramePtr&)>& sink)
      : source_(g,
                [this, &next](tbb::flow_control& fc) -> FramePtr {
                  FramePtr f = next();
                  if (!f) {
                    fc.stop();
                    return nullptr;
                  }
                  f->seq = seq_++;
                  return f;
                }),
        limiter_(g, std::max<std::size_t>(1, max_in_flight)),
        deliver_(g, tbb::flow::serial, [&sink](const FramePtr& f) {
          sink(f);
          return tbb::flow::continue_msg();
        }) {
    tbb::flow::make_edge(source_, limiter_);
    tbb::flow::make_edge(deliver_, limiter_.decrementer());
  }

  tbb::flow::limiter_node<FramePtr>& entry() { return limiter_; }
  InOrderNode<tbb::flow::continue_msg>& exit() { return deliver_; }

  /// Starts the source and waits until every frame has been delivered.
  void run(tbb::flow::graph& g) {
    source_.activate();
    g.wait_for_all();
  }

 private:
  std::uint64_t seq_ = 0;
  tbb::flow::input_node<FramePtr> source_;
  tbb::flow::limiter_node<FramePtr> limiter_;
  InOrderNode<tbb::flow::continue_msg> deliver_;
};

/// The stateless frame pipeline: source -> limiter(K) -> `routes` -> sequencer -> sink, frames
/// delivered in input order. Blocks until every frame is delivered (FramePipeline::run).
inline void run_stage_routes(std::size_t max_in_flight, const stages::FrameRoutes& routes,
                             const ReconstructionConfig& config,
                             const std::function<FramePtr()>& next,
                             const std::function<void(const FramePtr&)>& sink) {
  tbb::flow::graph g;
  FrameGraphEnds ends(g, max_in_flight, next, sink);
  tbb::flow::sequencer_node<FramePtr> in_order(g, [](const FramePtr& f) { return f->seq; });
  StageRoutes stage_routes(g, routes, config, in_order);
  tbb::flow::make_edge(ends.entry(), stage_routes.entry());
  tbb::flow::make_edge(in_order, ends.exit());
  ends.run(g);
}

}  // namespace meshflow::detail
