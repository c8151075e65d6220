#pragma once
// Shared by the Python module's files: the Cloud and Mesh objects and the conversions between
// NumPy arrays and meshflow's structures of arrays.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "nodes/triangulate/depth_triangulation.h"
#include "options/pipeline_options.h"
#include "runtime/depth_frame.h"
#include "runtime/point_cloud.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {
struct LiveResult;  // graph/live_pipeline.h
}  // namespace meshflow

namespace meshflow::python {

namespace py = pybind11;

/// A cloud shared between Python and the reconstruction (which copies it when it starts).
struct Cloud {
  std::shared_ptr<PointCloud> data = std::make_shared<PointCloud>();
};

/// A reconstructed mesh; `origin` is the world position of its local frame (georeferenced
/// inputs), which write() puts back.
struct Mesh {
  std::shared_ptr<TriangleMesh> data = std::make_shared<TriangleMesh>();
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
};

// An (n, columns) array over `values` (n items of `columns` Scalars each, packed), owned by
// `owner`: no copy. None when the vector is empty and `none_if_empty`.
template <typename Scalar, typename Item>
inline py::object view(const std::vector<Item>& values, py::ssize_t columns, py::handle owner,
                       bool none_if_empty) {
  static_assert(sizeof(Item) % sizeof(Scalar) == 0, "items are packed scalars");
  if (values.empty() && none_if_empty) return py::none();
  const auto n = static_cast<py::ssize_t>(values.size());
  return py::array_t<Scalar>(
      {n, columns},
      {static_cast<py::ssize_t>(sizeof(Item)), static_cast<py::ssize_t>(sizeof(Scalar))},
      reinterpret_cast<const Scalar*>(values.data()), owner);
}

// `array` as n x 3 values of type Scalar (cast by NumPy, any strides), or a ValueError naming
// `what` for another shape or a non-finite value.
template <typename Scalar>
inline py::array_t<Scalar, py::array::c_style | py::array::forcecast> rows_of_three(
    const py::handle& array, const char* what) {
  py::array_t<Scalar, py::array::c_style | py::array::forcecast> a;
  try {
    a = py::array_t<Scalar, py::array::c_style | py::array::forcecast>::ensure(array);
  } catch (const py::error_already_set&) {
    a = {};
  }
  if (!a) throw py::value_error(std::string(what) + ": expected an array of numbers");
  if (a.ndim() != 2 || a.shape(1) != 3) {
    std::string shape = "(";
    for (py::ssize_t d = 0; d < a.ndim(); ++d)
      shape += (d ? ", " : "") + std::to_string(a.shape(d));
    throw py::value_error(std::string(what) + ": expected shape (n, 3), got " + shape +
                          (a.ndim() == 1 ? ",)" : ")"));
  }
  if constexpr (std::is_floating_point_v<Scalar>) {
    const Scalar* p = a.data();
    for (py::ssize_t i = 0; i < a.shape(0) * 3; ++i) {
      if (!std::isfinite(p[i])) {
        throw py::value_error(std::string(what) + ": row " + std::to_string(i / 3) +
                              " is not finite (NaN or infinity)");
      }
    }
  }
  return a;
}

template <typename Item, typename Scalar>
inline std::vector<Item> copy_rows(
    const py::array_t<Scalar, py::array::c_style | py::array::forcecast>& a) {
  static_assert(sizeof(Item) == 3 * sizeof(Scalar), "items are three packed scalars");
  std::vector<Item> out(static_cast<std::size_t>(a.shape(0)));
  if (!out.empty())
    std::memcpy(static_cast<void*>(out.data()), a.data(), out.size() * sizeof(Item));
  return out;
}

/// A Cloud copied from (n, 3) arrays: points and normals (float32 after NumPy's cast, finite),
/// colours uint8 (integers 0-255, not floats), sensor_origin None or (x, y, z) metres.
/// ValueError naming the argument and the row for anything else.
Cloud make_cloud(const py::handle& points, const py::object& normals, const py::object& colors,
                 const py::object& sensor_origin);

/// A Mesh from (v, 3) vertices, (t, 3) vertex indices and optional (v, 3) normals and colours
/// (0-255), copied. ValueError naming the array for a wrong shape, a non-finite vertex, an index
/// out of range or a row count that does not match (python/module.cpp).
Mesh make_mesh(const py::handle& vertices, const py::handle& triangles, const py::object& normals,
               const py::object& colors);

/// A depth frame from NumPy: `depth` (h, w) uint16 (1/depth_scale metres, 0 = none) or float
/// (metres, 0 or NaN = none), `intrinsics` of the same size, `pose` a 4 x 4 camera-to-world
/// matrix (None: identity), `color` None or (h, w, 3) uint8. Copies the pixels. ValueError
/// naming the argument for a wrong shape or type; meshflow.Error (check_depth_frame) for
/// intrinsics that do not fit.
DepthFrame make_depth_frame(const py::handle& depth, const PinholeIntrinsics& intrinsics,
                            const py::object& pose, float depth_scale, const py::object& color);

/// The CLI's pipeline options from keyword arguments (`voxel`, `kn`, `extract`, `optimize`,
/// `normal_source` for --normals, `orient`, ... : option_list()); the rest keep the CLI's
/// defaults. TypeError for an unknown keyword or a value of the wrong type, ValueError with the
/// option model's message for a value out of range (python/options.cpp).
options::PipelineOptions pipeline_options(const py::kwargs& kwargs);

/// "the CLI's options, with its defaults: voxel=0.0, kn=10, ...", for messages and docstrings.
std::string option_list();

/// Sets the depth-map triangulation's method ('naive' or 'rqt') and decimation share (in
/// [0, 1), 0 = off); ValueError naming the argument otherwise (python/depth.cpp).
void set_triangulation(DepthTriangulationConfig& config, const std::string& method, float decimate);

/// Binds Intrinsics, triangulate_depth and TsdfVolume (python/depth.cpp).
void bind_depth(py::module_& m);

/// Binds Pipeline, the embedding API (python/live.cpp).
void bind_live(py::module_& m);

/// Binds read_depth, read_color, read_trajectory and read_intrinsics (python/readers.cpp).
void bind_readers(py::module_& m);

/// Binds compress and decompress (python/compress.cpp).
void bind_compress(py::module_& m);

/// Binds serve and ServedView, when built with the serving layer (python/serve.cpp).
void bind_serve(py::module_& m);

/// A Pipeline's viewer (meshflow.Pipeline(serve=...)): each finished frame's stats and newest
/// mesh go to the browsers as `meshflow live --serve` sends them; never waits on the network.
class LiveView {
 public:
  virtual ~LiveView() = default;
  /// A finished frame, from a pipeline thread (one call at a time, no GIL needed); copies the
  /// mesh into the encoder's one-mesh slot. O(mesh).
  virtual void frame(const LiveResult& result) = 0;
  /// Publishes the newest mesh (viewers or not) and the end of the run, then stops serving
  /// once every connected viewer was sent the end (at most 5 s; closes every connection).
  /// Blocks for that one encoding and the wait; idempotent.
  virtual void close() = 0;
  /// The page's URL, http://HOST:PORT/.
  virtual std::string url() const = 0;
};

/// Starts a Pipeline's viewer: `address` an int port (on 127.0.0.1; 0 = any free port) or a
/// "[HOST:]PORT" string as the CLI's --serve takes it, `serve_rate` Mbit/s per viewer (0: no
/// cap), `max_viewers` browsers at once. TypeError / ValueError with the option model's
/// messages; meshflow.Error for a port in use, or when the module was built without the
/// serving layer (python/serve.cpp, python/serve_off.cpp).
std::unique_ptr<LiveView> start_live_view(const py::object& address, const py::object& serve_rate,
                                          const py::object& max_viewers);

}  // namespace meshflow::python
