// meshflow.serve: a mesh (a Mesh or a file) shown in the browser by the serving layer, as
// `meshflow view` shows it. Settings are the option model's serving options
// (options/serve_options.h), checked by the same checks with the same messages as the CLI's.

#include <pybind11/stl.h>

#include <memory>
#include <string>
#include <variant>

#include "bindings.h"
#include "options/serve_options.h"
#include "runtime/error.h"
#include "tools/viewer_server.h"

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
            const auto wide = value.cast<long long>();
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

}  // namespace

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
        if (!py::isinstance<py::int_>(port) || py::isinstance<py::bool_>(port))
          throw py::type_error("port: expected an int, got " + std::string(py::repr(port)));
        options::ServeOptions o;
        const std::string port_text = std::to_string(port.cast<long long>());
        o.address = host.find(':') != std::string::npos ? "[" + host + "]:" + port_text
                                                        : host + ":" + port_text;
        try {
          options::parse_serve_address(o.address);
        } catch (const Error& e) {
          throw py::value_error("host, port: " + e.problem());
        }
        set_serve_option(o, "serve-rate", serve_rate, "serve_rate");
        set_serve_option(o, "max-viewers", max_viewers, "max_viewers");

        cli::ViewImage image;
        std::string name;
        if (py::isinstance<Mesh>(mesh_or_path)) {
          const Mesh& mesh = mesh_or_path.cast<const Mesh&>();
          name = "mesh";
          compress::CompressConfig config = cli::view_compress_config();
          config.origin_offset = mesh.origin;
          py::gil_scoped_release no_gil;
          image = cli::view_image_of_mesh(*mesh.data, config, name);
        } else {
          name = py::str(py::module_::import("os").attr("fspath")(mesh_or_path));
          py::gil_scoped_release no_gil;
          image = cli::view_image_of_file(name, cli::view_compress_config());
        }
        const auto mfc = std::make_shared<const std::string>(image.mfc.begin(), image.mfc.end());
        std::unique_ptr<serve::Server> server;
        {
          py::gil_scoped_release no_gil;
          server = cli::start_viewer_server(o, 64 * 1024,
                                            {{"/mesh.mfc", {"application/octet-stream", mfc}}});
          cli::publish_view(*server, image, "meshflow.serve", name);
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
