// meshflow.serve: a mesh (a Mesh or a file) shown in the browser by the serving layer, as
// `meshflow view` shows it. Settings are the option model's serving options
// (options/serve_options.h), checked by the same checks with the same messages as the CLI's.

#include <pybind11/stl.h>

#include <chrono>
#include <climits>
#include <memory>
#include <string>
#include <thread>
#include <variant>

#include "bindings.h"
#include "graph/live_pipeline.h"
#include "options/serve_options.h"
#include "runtime/error.h"
#include "serve/run_publisher.h"
#include "serve/viewer_server.h"

namespace meshflow::python {
namespace {

// A running server; close() (or leaving a `with` block, or collection) stops it.
class ServedView {
 public:
  explicit ServedView(std::unique_ptr<serve::Server> server) : server_(std::move(server)) {
    url_ = server_->url();
    host_ = server_->host();
    port_ = server_->port();
  }
  ~ServedView() { close(); }

  void close() {
    if (!server_) return;
    py::gil_scoped_release no_gil;  // joins the I/O thread
    server_.reset();
  }
  bool open() const { return server_ != nullptr; }
  const std::string& url() const { return url_; }
  const std::string& host() const { return host_; }
  int port() const { return port_; }
  py::dict stats() const {
    py::dict d;
    if (!server_) return d;
    const serve::ServerStats s = server_->stats();
    d["viewers"] = s.clients;
    d["viewers_accepted"] = s.clients_accepted;
    d["frames_sent"] = s.frames_sent;
    d["bytes_sent"] = s.bytes_sent;
    d["http_requests"] = s.http_requests;
    return d;
  }

 private:
  std::unique_ptr<serve::Server> server_;
  std::string url_, host_;
  int port_ = 0;
};

// A Python int as a long long, saturated (10**30 becomes LLONG_MAX) so that the model's range
// check names it rather than pybind11 failing the conversion.
long long saturated_int(const py::handle& value) {
  int overflow = 0;
  const long long v = PyLong_AsLongLongAndOverflow(value.ptr(), &overflow);
  if (overflow != 0) return overflow > 0 ? LLONG_MAX : LLONG_MIN;
  if (v == -1 && PyErr_Occurred()) throw py::error_already_set();
  return v;
}

// Sets the serving option named `name` (CLI spelling) in `o` from a Python value and runs the
// model's check: TypeError for a value of another type, ValueError with the model's message.
void set_serve_option(options::ServeOptions& o, const std::string& name, const py::handle& value,
                      const std::string& python_name) {
  for (const options::ServeOptionSpec& spec : options::serve_option_specs()) {
    if (name != spec.name) continue;
    std::visit(
        [&](auto member) {
          using T = std::remove_reference_t<decltype(o.*member)>;
          const bool number =
              (py::isinstance<py::int_>(value) ||
               (std::is_floating_point_v<T> && py::isinstance<py::float_>(value))) &&
              !py::isinstance<py::bool_>(value);
          if (!number)
            throw py::type_error(python_name + ": expected a number, got " +
                                 std::string(py::repr(value)));
          if constexpr (std::is_unsigned_v<T>) {
            const long long wide = saturated_int(value);
            if (wide < 0)
              throw py::value_error(python_name + ": " +
                                    options::check_number(static_cast<double>(wide), 0, 0));
            o.*member = static_cast<T>(wide);
          } else if constexpr (!std::is_same_v<T, std::string>) {
            o.*member = value.cast<T>();
          }
        },
        spec.field);
    const std::string problem = spec.check(o);
    if (!problem.empty()) throw py::value_error(python_name + ": " + problem);
    return;
  }
  throw std::logic_error("serve option '" + name + "' is not in the option model");
}

// Serving options from Python's spelling: the address as the CLI's --serve takes it, checked by
// the model's parser (ValueError naming `address_name`), then the rate and the viewer limit.
options::ServeOptions python_serve_options(const std::string& address,
                                           const std::string& address_name,
                                           const py::object& serve_rate,
                                           const py::object& max_viewers) {
  options::ServeOptions o;
  o.address = address;
  try {
    options::parse_serve_address(o.address);
  } catch (const Error& e) {
    throw py::value_error(address_name + ": " + e.problem());
  }
  set_serve_option(o, "serve-rate", serve_rate, "serve_rate");
  set_serve_option(o, "max-viewers", max_viewers, "max_viewers");
  return o;
}

// An int port as "PORT" (saturated: the parser names a port out of range).
std::string port_text(const py::object& port, const char* name) {
  if (!py::isinstance<py::int_>(port) || py::isinstance<py::bool_>(port))
    throw py::type_error(std::string(name) + ": expected an int, got " +
                         std::string(py::repr(port)));
  return std::to_string(saturated_int(port));
}

// A Pipeline's viewer: the server with the page and the run's publisher (serve/run_publisher.h).
class ServedLiveView final : public LiveView {
 public:
  explicit ServedLiveView(const options::ServeOptions& o)
      : server_(serve::start_viewer_server(o)),
        publisher_(std::make_unique<serve::RunPublisher>(*server_, "meshflow.Pipeline")) {
    url_ = server_->url();
  }
  ~ServedLiveView() override { close(); }

  void frame(const LiveResult& result) override {
    if (publisher_) publisher_->frame(result);
  }
  void close() override {
    if (!publisher_) return;
    publisher_->finish();
    publisher_.reset();
    // The viewers connected now get what was queued for them and the end before the server
    // stops (at most 5 s: a stalled viewer does not hold up the program).
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (std::chrono::steady_clock::now() < deadline) {
      const serve::ServerStats s = server_->stats();
      if (s.ends_sent >= s.clients) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    server_.reset();
  }
  std::string url() const override { return url_; }

 private:
  std::unique_ptr<serve::Server> server_;
  std::unique_ptr<serve::RunPublisher> publisher_;
  std::string url_;
};

}  // namespace

std::unique_ptr<LiveView> start_live_view(const py::object& address, const py::object& serve_rate,
                                          const py::object& max_viewers) {
  const std::string text =
      py::isinstance<py::str>(address) ? address.cast<std::string>() : port_text(address, "serve");
  const options::ServeOptions o = python_serve_options(text, "serve", serve_rate, max_viewers);
  py::gil_scoped_release no_gil;
  return std::make_unique<ServedLiveView>(o);
}

void bind_serve(py::module_& m) {
  py::class_<ServedView>(m, "ServedView",
                         "A mesh served to browsers (meshflow.serve); close() stops the server.")
      .def_property_readonly("url", &ServedView::url, "The page's URL: http://HOST:PORT/")
      .def_property_readonly("host", &ServedView::host, "The address bound")
      .def_property_readonly("port", &ServedView::port, "The port bound (the one chosen for 0)")
      .def_property_readonly("open", &ServedView::open, "Whether it still serves")
      .def("stats", &ServedView::stats,
           "What was served so far: viewers, viewers_accepted, frames_sent, bytes_sent, "
           "http_requests (empty once closed)")
      .def("close", &ServedView::close, "Stops serving (closes every connection); idempotent")
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__", [](ServedView& self, const py::args&) { self.close(); });

  m.def(
      "serve",
      [](const py::object& mesh_or_path, const py::object& port, const std::string& host,
         const py::object& serve_rate, const py::object& max_viewers) {
        // The address as the CLI's --serve takes it, checked by the model's parser.
        const std::string port_part = port_text(port, "port");
        const options::ServeOptions o =
            python_serve_options(host.find(':') != std::string::npos ? "[" + host + "]:" + port_part
                                                                     : host + ":" + port_part,
                                 "host, port", serve_rate, max_viewers);

        serve::ViewImage image;
        std::string name;
        if (py::isinstance<Mesh>(mesh_or_path)) {
          const Mesh& mesh = mesh_or_path.cast<const Mesh&>();
          name = "mesh";
          compress::CompressConfig config = serve::view_compress_config();
          config.origin_offset = mesh.origin;
          py::gil_scoped_release no_gil;
          image = serve::view_image_of_mesh(*mesh.data, config, name);
        } else {
          name = py::str(py::module_::import("os").attr("fspath")(mesh_or_path));
          py::gil_scoped_release no_gil;
          image = serve::view_image_of_file(name, serve::view_compress_config());
        }
        const auto mfc = std::make_shared<const std::string>(image.mfc.begin(), image.mfc.end());
        std::unique_ptr<serve::Server> server;
        {
          py::gil_scoped_release no_gil;
          server = serve::start_viewer_server(o, 64 * 1024,
                                              {{"/mesh.mfc", {"application/octet-stream", mfc}}});
          serve::publish_view(*server, image, "meshflow.serve", name);
        }
        return std::make_unique<ServedView>(std::move(server));
      },
      py::arg("mesh"), py::arg("port") = 8080, py::arg("host") = "127.0.0.1",
      py::arg("serve_rate") = 0.0, py::arg("max_viewers") = 8,
      R"(Shows a mesh in the browser, as `meshflow view` does: mesh is a meshflow.Mesh or the
path of a mesh file (.ply .obj .off .stl) or a .mfc file. The mesh is encoded with meshflow's
progressive codec and served with the viewer page at http://HOST:PORT/ (host 127.0.0.1 unless
given: safe by default; port 0: any free port), the whole .mfc image also at /mesh.mfc. The
server runs on its own thread until close() (or the end of a `with` block). serve_rate caps
each viewer's bandwidth, Mbit/s (0: none); max_viewers browsers at once. The settings are the
CLI's --serve, --serve-rate and --max-viewers, checked the same way: ValueError with the same
message for a bad address or value, meshflow.Error for a port in use (naming the address) or a
file that cannot be read. Returns a ServedView (url, host, port, stats(), close()).)");
}

}  // namespace meshflow::python
