#pragma once
// Flow-graph parts every frame pipeline shares (internal to graph/): the numbered source feeding
// a limiter of K frames in flight, the serial delivery to the sink that releases the limiter,
// and the node body that runs one stateless stage.

#include <oneapi/tbb/flow_graph.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <memory>
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

/// One unlimited node per stage of stages::frame_stages(triangulate_depth_maps,
/// config.compression, config.close.enabled) (frames overlap in every stage), each joined to the
/// next; the caller connects front() and back(). `config` must outlive the chain.
class StageChain {
 public:
  StageChain(tbb::flow::graph& g, bool triangulate_depth_maps, const ReconstructionConfig& config)
      : StageChain(
            g,
            stages::frame_stages(triangulate_depth_maps, config.compression, config.close.enabled),
            config) {}
  /// The same over any non-empty list of stages.
  StageChain(tbb::flow::graph& g, const std::vector<stages::NamedStage>& stage_list,
             const ReconstructionConfig& config) {
    for (const stages::NamedStage& stage : stage_list)
      nodes_.push_back(std::make_unique<StageNode>(g, tbb::flow::unlimited,
                                                   StageNodeBody(stage.name, stage.body, config)));
    for (std::size_t i = 1; i < nodes_.size(); ++i)
      tbb::flow::make_edge(*nodes_[i - 1], *nodes_[i]);
  }
  StageNode& front() { return *nodes_.front(); }
  StageNode& back() { return *nodes_.back(); }

 private:
  std::vector<std::unique_ptr<StageNode>> nodes_;
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

/// The stateless frame pipeline: source -> limiter(K) -> `stage_list` -> sequencer -> sink,
/// frames delivered in input order. Blocks until every frame is delivered (FramePipeline::run).
inline void run_stage_chain(std::size_t max_in_flight,
                            const std::vector<stages::NamedStage>& stage_list,
                            const ReconstructionConfig& config,
                            const std::function<FramePtr()>& next,
                            const std::function<void(const FramePtr&)>& sink) {
  tbb::flow::graph g;
  FrameGraphEnds ends(g, max_in_flight, next, sink);
  StageChain chain(g, stage_list, config);
  tbb::flow::sequencer_node<FramePtr> in_order(g, [](const FramePtr& f) { return f->seq; });
  tbb::flow::make_edge(ends.entry(), chain.front());
  tbb::flow::make_edge(chain.back(), in_order);
  tbb::flow::make_edge(in_order, ends.exit());
  ends.run(g);
}

}  // namespace meshflow::detail
