#include "graph/live_pipeline.h"

#include <oneapi/tbb/flow_graph.h>
#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <condition_variable>
#include <deque>
#include <iterator>
#include <mutex>

#include "graph/frame_graph.h"
#include "runtime/error.h"

namespace meshflow {
namespace flow = tbb::flow;

namespace {
constexpr std::size_t kLatencyWindow = 4096;

int arena_threads(const LiveConfig& c) {
  return c.threads > 0 ? c.threads : tbb::this_task_arena::max_concurrency();
}

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  const std::size_t k =
      std::min(values.size() - 1, static_cast<std::size_t>(q * static_cast<double>(values.size())));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}
}  // namespace

struct LivePipeline::Impl {
  LiveConfig config;
  Callback callback;
  // Nobody joins the arena (push() only enqueues), so all its threads must be workers; oneTBB
  // caps workers at (allowed parallelism - 1) for the whole process, so the cap is raised by
  // one while the pipeline lives (an application's own lower cap still wins: the minimum of
  // the active controls applies).
  tbb::global_control workers;
  tbb::task_arena arena;
  std::unique_ptr<flow::graph> graph;  // made inside `arena`: a graph runs in its creator's arena

  mutable std::mutex mutex;         // guards everything below
  std::condition_variable settled;  // in_flight == 0 and waiting empty
  std::deque<FramePtr> waiting;
  std::size_t in_flight = 0;
  std::uint64_t next_push = 0, next_dispatch = 0;
  bool closing = false;
  LiveStats counts;
  std::vector<double> latencies;  // ring of the last kLatencyWindow
  std::size_t latency_at = 0;

  // The graph: stage routes -> in-order -> deliver. Built inside the arena so its tasks run
  // there.
  std::unique_ptr<flow::sequencer_node<FramePtr>> in_order;
  std::unique_ptr<detail::StageRoutes> routes;
  std::unique_ptr<detail::InOrderNode<flow::continue_msg>> deliver;

  Impl(LiveConfig c, Callback cb)
      : config(std::move(c)),
        callback(std::move(cb)),
        workers(tbb::global_control::max_allowed_parallelism, arena_threads(config) + 1),
        arena(arena_threads(config), 0) {
    config.frames_in_flight = std::max<std::size_t>(1, config.frames_in_flight);
    config.max_waiting = std::max<std::size_t>(1, config.max_waiting);
    latencies.reserve(kLatencyWindow);  // no allocation per frame once running
    arena.execute([&] {
      graph = std::make_unique<flow::graph>();
      build_graph();
    });
  }

  void build_graph() {
    in_order = std::make_unique<flow::sequencer_node<FramePtr>>(
        *graph, [](const FramePtr& f) { return f->seq; });
    const ReconstructionConfig& rc = config.reconstruction;
    routes = std::make_unique<detail::StageRoutes>(
        *graph,
        stages::frame_routes(config.triangulate_depth_maps, rc.compression, rc.close.enabled), rc,
        *in_order);
    deliver = std::make_unique<detail::InOrderNode<flow::continue_msg>>(
        *graph, flow::serial, [this](const FramePtr& f) {
          finish(f);
          return flow::continue_msg();
        });
    flow::make_edge(*in_order, *deliver);
  }

  // Numbers a frame for the sequencer and counts it in flight; call with the mutex held, then
  // start() it after unlocking.
  void dispatch_locked(const FramePtr& f) {
    f->seq = next_dispatch++;
    ++in_flight;
  }
  // Hands f to the first stage. From a thread outside the arena, try_put submits the node's
  // task into the graph's arena and returns at once (arena.execute would wait for a free slot
  // while the workers are busy, blocking push()).
  void start(const FramePtr& f) { routes->entry().try_put(f); }

  Push push(const FramePtr& f) {
    f->submitted_s = monotonic_seconds();
    FramePtr to_start;
    Push result{PushStatus::kAccepted, 0};
    {
      std::lock_guard<std::mutex> lock(mutex);
      result.seq = next_push++;
      f->source_index = result.seq;
      f->name = "frame " + std::to_string(result.seq);
      ++counts.pushed;
      if (closing) {
        result.status = PushStatus::kRejected;
        ++counts.rejected;
        return result;
      }
      if (in_flight < config.frames_in_flight) {
        dispatch_locked(f);
        to_start = f;
      } else if (waiting.size() < config.max_waiting) {
        waiting.push_back(f);
      } else if (config.policy == LivePolicy::kRealtime) {
        waiting.pop_front();
        ++counts.dropped;
        waiting.push_back(f);
        result.status = PushStatus::kAcceptedDroppedOldest;
      } else {
        ++counts.rejected;
        result.status = PushStatus::kRejected;
      }
    }
    if (to_start) start(to_start);
    return result;
  }

  // The serial end of the graph: one finished frame, in dispatch order.
  void finish(const FramePtr& f) {
    LiveResult r;
    r.seq = f->source_index;
    r.ok = f->ok();
    r.error = f->error;
    r.failed_stage = f->failed_stage;
    r.mesh = std::move(f->mesh);
    r.compressed = std::move(f->compressed);
    r.timings = std::move(f->timings);
    r.latency_s = monotonic_seconds() - f->submitted_s;
    bool deliver_it = false;
    {
      std::lock_guard<std::mutex> lock(mutex);
      deliver_it = !closing;
    }
    bool threw = false;
    if (deliver_it) {
      try {
        callback(r);
      } catch (...) {  // the contract says it must not throw; the pipeline keeps going
        threw = true;
      }
    }
    FramePtr next;
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (deliver_it) {
        ++counts.delivered;
        counts.failed += r.ok ? 0 : 1;
        counts.callback_exceptions += threw ? 1 : 0;
        if (latencies.size() < kLatencyWindow)
          latencies.push_back(r.latency_s);
        else
          latencies[latency_at] = r.latency_s;
        latency_at = (latency_at + 1) % kLatencyWindow;
      }
      --in_flight;
      if (!waiting.empty() && !closing) {
        next = waiting.front();
        waiting.pop_front();
        dispatch_locked(next);
      }
      if (in_flight == 0 && waiting.empty()) settled.notify_all();
    }
    if (next) routes->entry().try_put(next);  // already on a graph thread
  }

  void wait_settled() {
    std::unique_lock<std::mutex> lock(mutex);
    settled.wait(lock, [&] { return in_flight == 0 && waiting.empty(); });
  }
};

LivePipeline::LivePipeline(LiveConfig config, Callback callback) {
  if (!callback) throw Error("LivePipeline", "callback", "must not be empty");
  impl_ = std::make_unique<Impl>(std::move(config), std::move(callback));
}

LivePipeline::~LivePipeline() {
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->closing = true;
    impl_->waiting.clear();
  }
  impl_->wait_settled();
  // The last finish() has returned to the graph; let its task end before the nodes go.
  impl_->arena.execute([&] { impl_->graph->wait_for_all(); });
}

LivePipeline::Push LivePipeline::push(PointCloud cloud, double timestamp_s) {
  auto f = std::make_shared<Frame>();
  f->timestamp_s = timestamp_s;
  f->cloud = std::move(cloud);  // the read stage keeps it (no loader)
  return impl_->push(f);
}

LivePipeline::Push LivePipeline::push(DepthFrame frame) {
  auto f = std::make_shared<Frame>();
  f->timestamp_s = frame.timestamp_s;
  auto depth = std::make_shared<DepthFrame>(std::move(frame));
  f->load_depth = [depth] { return *depth; };
  return impl_->push(f);
}

void LivePipeline::flush() { impl_->wait_settled(); }

LiveStats LivePipeline::stats() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  LiveStats s = impl_->counts;
  s.waiting = impl_->waiting.size();
  s.in_flight = impl_->in_flight;
  s.latency_p50_s = percentile(impl_->latencies, 0.50);
  s.latency_p95_s = percentile(impl_->latencies, 0.95);
  s.latency_p99_s = percentile(impl_->latencies, 0.99);
  return s;
}

}  // namespace meshflow
