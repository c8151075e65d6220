// The embedding API from Python: meshflow.Pipeline pushes clouds or depth frames and calls a
// Python function with each finished mesh, on a pipeline thread (holding the GIL only for the
// call).

#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include <chrono>
#include <memory>
#include <string>
#include <thread>
#include <utility>

#include "graph/live_pipeline.h"
#include "python/bindings.h"
#include "runtime/error.h"

namespace meshflow::python {

/// meshflow.FrameDroppedWarning (a RuntimeWarning subclass).
py::handle frame_dropped_warning();

namespace {

/// What the callback receives for one frame.
struct Result {
  std::uint64_t seq = 0;
  bool ok = false;
  std::string error, failed_stage;
  py::object mesh = py::none();  ///< a Mesh, or None for a failed frame
  double latency_s = 0.0;
};

// A LivePipeline and the Python callable it calls. The pipeline's C++ callback holds only a
// pointer to this object (no Python object: destroying the pipeline happens without the GIL).
// Every call into the pipeline releases the GIL first: a callback thread may be waiting for the
// GIL while it holds a lock of the pipeline's that the call needs.
class Pipeline {
 public:
  /// `wait_for_room`: the 'offline' policy (a kQueue pipeline whose push() waits instead of
  /// refusing a frame).
  /// `view`: the browsers' viewer (Pipeline(serve=...)), or nullptr.
  Pipeline(py::function callback, const LiveConfig& config, bool wait_for_room,
           std::unique_ptr<LiveView> view)
      : callback_(std::move(callback)),
        wait_for_room_(wait_for_room),
        max_waiting_(config.max_waiting),
        view_(std::move(view)) {
    live_ = std::make_unique<LivePipeline>(config, [this](LiveResult& r) { deliver(r); });
  }
  ~Pipeline() { close(); }
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  py::tuple push_cloud(const py::object& input, double timestamp_s) {
    // A Cloud is copied (Python keeps it); arrays are copied once, by make_cloud.
    PointCloud frame = py::isinstance<Cloud>(input)
                           ? *input.cast<Cloud>().data
                           : std::move(*make_cloud(input, py::none(), py::none(), py::none()).data);
    return push(std::move(frame), timestamp_s);
  }

  py::tuple push_depth(DepthFrame frame) {
    const double timestamp_s = frame.timestamp_s;
    return push(std::move(frame), timestamp_s);
  }

  void flush() {
    py::gil_scoped_release no_gil;  // callbacks need the GIL to finish
    open().flush();
  }

  LiveStats stats() const {
    if (!live_) throw Error("Pipeline", "", "the pipeline is closed");
    // Without the GIL: a callback waiting for it may hold the pipeline's own lock.
    py::gil_scoped_release no_gil;
    return live_->stats();
  }

  /// Stops the pipeline (waiting frames are discarded; flush() first to keep them), then the
  /// viewer: the newest mesh and the end go out, and the server stops.
  void close() {
    if (!live_) return;
    py::gil_scoped_release no_gil;
    live_.reset();
    if (view_) view_->close();
  }

  /// The viewer page's URL, or None without serve=.
  py::object url() const { return view_ ? py::cast(view_->url()) : py::none(); }

 private:
  LivePipeline& open() {
    if (!live_) throw Error("Pipeline", "", "the pipeline is closed");
    return *live_;
  }

  // Pushes a cloud or depth frame. 'offline': first waits (polling every millisecond, without
  // the GIL) until the queue has room, so the frame is neither refused nor dropped (a push from
  // the callback does not wait). A frame
  // dropped or refused (policy 'realtime' or 'queue'; or an offline pipeline that a callback
  // pushes into as well) raises FrameDroppedWarning, shown once per call site by Python's
  // default warning filter.
  template <typename Input>
  py::tuple push(Input frame, double timestamp_s) {
    LivePipeline::Push p{};
    {
      py::gil_scoped_release no_gil;
      LivePipeline& live = open();
      // Not from a callback: its pipeline thread waiting for room would stop the deliveries
      // that make room.
      while (wait_for_room_ && !delivering_ && live.stats().waiting >= max_waiting_)
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      p = push_one(live, std::move(frame), timestamp_s);
    }
    if (p.status == LivePipeline::PushStatus::kAcceptedDroppedOldest)
      warn_dropped("the oldest waiting frame was dropped for frame " + std::to_string(p.seq) +
                   " (policy 'realtime' keeps latency bounded)");
    else if (p.status == LivePipeline::PushStatus::kRejected)
      warn_dropped("frame " + std::to_string(p.seq) +
                   " was refused: the queue is full (policy 'queue'; push it again later)");
    return status(p);
  }

  static LivePipeline::Push push_one(LivePipeline& live, PointCloud cloud, double timestamp_s) {
    return live.push(std::move(cloud), timestamp_s);
  }
  static LivePipeline::Push push_one(LivePipeline& live, DepthFrame frame, double) {
    return live.push(std::move(frame));
  }

  static void warn_dropped(const std::string& what) {
    const std::string message =
        "meshflow.Pipeline: " + what +
        "; for offline use, where every frame counts, use policy='offline' (push() then waits "
        "for room)";
    if (PyErr_WarnEx(frame_dropped_warning().ptr(), message.c_str(), 1) != 0)
      throw py::error_already_set();  // warnings turned into errors
  }

  static py::tuple status(const LivePipeline::Push& p) {
    const char* name = p.status == LivePipeline::PushStatus::kAccepted ? "accepted"
                       : p.status == LivePipeline::PushStatus::kAcceptedDroppedOldest
                           ? "dropped_oldest"
                           : "rejected";
    return py::make_tuple(p.seq, name);
  }

  // On a pipeline thread: takes the GIL for the Python call only. An exception in the callback
  // is printed as Python prints one from a thread, and counted (stats()["callback_exceptions"]).
  void deliver(LiveResult& r) {
    if (view_) view_->frame(r);  // copies the mesh; before the GIL, which it does not need
    py::gil_scoped_acquire gil;
    Result result;
    result.seq = r.seq;
    result.ok = r.ok;
    result.error = r.error;
    result.failed_stage = r.failed_stage;
    result.latency_s = r.latency_s;
    if (r.ok) {
      Mesh mesh;
      *mesh.data = std::move(r.mesh);
      result.mesh = py::cast(std::move(mesh));
    }
    delivering_ = true;  // a push() from the callback must not wait for room
    struct Reset {
      ~Reset() { delivering_ = false; }
    } reset;
    try {
      callback_(std::move(result));
    } catch (py::error_already_set& e) {
      e.discard_as_unraisable("meshflow.Pipeline callback");
      throw std::runtime_error("the Python callback raised");
    }
  }

  py::function callback_;
  bool wait_for_room_ = false;
  std::size_t max_waiting_ = 1;
  static thread_local bool delivering_;  ///< this thread is in the Python callback
  std::unique_ptr<LiveView> view_;       ///< outlives live_ (whose threads call it)
  std::unique_ptr<LivePipeline> live_;
};

thread_local bool Pipeline::delivering_ = false;

py::dict stats_dict(const LiveStats& s) {
  py::dict d;
  d["pushed"] = s.pushed;
  d["rejected"] = s.rejected;
  d["dropped"] = s.dropped;
  d["delivered"] = s.delivered;
  d["failed"] = s.failed;
  d["callback_exceptions"] = s.callback_exceptions;
  d["waiting"] = s.waiting;
  d["in_flight"] = s.in_flight;
  d["latency_p50_s"] = s.latency_p50_s;
  d["latency_p95_s"] = s.latency_p95_s;
  d["latency_p99_s"] = s.latency_p99_s;
  return d;
}

}  // namespace

py::handle frame_dropped_warning() {
  // Created once with the module (bind_live), never freed: the module lives as long.
  static py::handle warning = PyErr_NewExceptionWithDoc(
      "meshflow.FrameDroppedWarning",
      "A Pipeline dropped or refused a pushed frame (policy 'realtime' or 'queue').",
      PyExc_RuntimeWarning, nullptr);
  return warning;
}

void bind_live(py::module_& m) {
  m.attr("FrameDroppedWarning") = frame_dropped_warning();
  py::class_<Result>(m, "Result", "One finished frame, as a Pipeline's callback receives it.")
      .def_readonly("seq", &Result::seq, "what push() returned for the frame")
      .def_readonly("ok", &Result::ok)
      .def_readonly("error", &Result::error, "when not ok: what went wrong")
      .def_readonly("failed_stage", &Result::failed_stage)
      .def_readonly("mesh", &Result::mesh, "a Mesh, or None when not ok")
      .def_readonly("latency_s", &Result::latency_s, "from push() to the callback, seconds")
      .def("__repr__", [](const Result& r) {
        return "<meshflow.Result seq " + std::to_string(r.seq) + (r.ok ? " ok" : " failed") + ">";
      });

  py::class_<Pipeline>(m, "Pipeline", R"(The embedding API: push() clouds or depth frames from
your loop, callback(result) is called with each finished frame in push order on a pipeline
thread. policy 'realtime' (a live sensor; push() never waits) drops the oldest waiting frame
when the queue is full (bounded latency), 'queue' refuses new ones (back-pressure): both raise
a meshflow.FrameDroppedWarning when they do. 'offline' (files, a script's loop) never drops or
refuses: push() waits until the queue has room. threads: the
pipeline's own threads (0 = every core); triangulate: per-frame depth-map meshes (method 'naive'
or 'rqt', decimate in [0, 1)) instead of the volumetric stages, whose settings are the other
keywords, as reconstruct()'s. serve: show the meshes in browsers while they are made, as
`meshflow live --serve` does: a port (on 127.0.0.1; 0 = any free port) or '[HOST:]PORT'; url
gives the page, serve_rate (Mbit/s per viewer, 0: no cap) and max_viewers as meshflow.serve();
the viewer never slows the pipeline, and close() publishes the last mesh and stops serving.)")
      .def(py::init([](py::function callback, const std::string& policy, int threads,
                       std::size_t frames_in_flight, std::size_t max_waiting, bool triangulate,
                       const std::string& method, float decimate, const py::object& serve,
                       const py::object& serve_rate, const py::object& max_viewers,
                       const py::kwargs& options) {
             LiveConfig c;
             if (policy == "realtime") {
               c.policy = LivePolicy::kRealtime;
             } else if (policy == "queue" || policy == "offline") {
               c.policy = LivePolicy::kQueue;
             } else {
               throw py::value_error("policy: expected 'realtime', 'queue' or 'offline', got '" +
                                     policy + "'");
             }
             if (frames_in_flight < 1 || max_waiting < 1)
               throw py::value_error("frames_in_flight and max_waiting: at least 1");
             const options::PipelineOptions o = pipeline_options(options);  // TypeError if unknown
             try {
               c.reconstruction = o.config();
             } catch (const std::exception& e) {  // a malformed orient, extract, optimize, ...
               throw py::value_error(e.what());
             }
             set_triangulation(c.reconstruction.triangulation, method, decimate);
             c.threads = threads;
             c.frames_in_flight = frames_in_flight;
             c.max_waiting = max_waiting;
             c.triangulate_depth_maps = triangulate;
             std::unique_ptr<LiveView> view =
                 serve.is_none() ? nullptr : start_live_view(serve, serve_rate, max_viewers);
             return std::make_unique<Pipeline>(std::move(callback), c, policy == "offline",
                                               std::move(view));
           }),
           py::arg("callback"), py::kw_only(), py::arg("policy") = "realtime",
           py::arg("threads") = 0, py::arg("frames_in_flight") = LiveConfig{}.frames_in_flight,
           py::arg("max_waiting") = LiveConfig{}.max_waiting, py::arg("triangulate") = false,
           py::arg("method") = "naive", py::arg("decimate") = 0.0f, py::arg("serve") = py::none(),
           py::arg("serve_rate") = 0.0, py::arg("max_viewers") = 8)
      .def("push", &Pipeline::push_cloud, py::arg("cloud"), py::arg("timestamp") = 0.0,
           "Hands over a Cloud or (n, 3) points; returns (seq, 'accepted' | 'dropped_oldest' | "
           "'rejected').")
      .def(
          "push_depth",
          [](Pipeline& p, const py::handle& depth, const PinholeIntrinsics& intrinsics,
             const py::object& pose, float depth_scale, const py::object& color, double timestamp) {
            DepthFrame frame = make_depth_frame(depth, intrinsics, pose, depth_scale, color);
            frame.timestamp_s = timestamp;
            return p.push_depth(std::move(frame));
          },
          py::arg("depth"), py::arg("intrinsics"), py::arg("pose") = py::none(),
          py::arg("depth_scale") = 1000.0f, py::arg("color") = py::none(),
          py::arg("timestamp") = 0.0, "Hands over a depth image; returns as push().")
      .def("flush", &Pipeline::flush,
           "Waits until every accepted, undropped frame has reached the callback.")
      .def("stats", [](const Pipeline& p) { return stats_dict(p.stats()); })
      .def_property_readonly("url", &Pipeline::url, "The viewer page's URL (serve=), or None")
      .def("close", &Pipeline::close, "Stops the pipeline; waiting frames are discarded.")
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__", [](Pipeline& p, const py::args&) {
        p.flush();
        p.close();
      });
}

}  // namespace meshflow::python
