// meshflow's Python module (pybind11): read a cloud, reconstruct a mesh, write it, with NumPy
// arrays in and out. The reconstruction settings are the CLI's options under the same names
// and defaults (tools/pipeline_options: the same code builds the stages' configuration), so
// meshflow.reconstruct(meshflow.read_cloud(path)) gives the triangles `meshflow reconstruct`
// writes for that file.
//
// Arrays handed out (Cloud.points, Mesh.vertices, ...) are views of the C++ vectors, not copies:
// their `base` is the Cloud or Mesh, which they keep alive. Arrays handed in are copied once
// into meshflow's structure of arrays (any dtype NumPy can cast to float32 / uint8, any strides).

#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "python/bindings.h"

#include "graph/pipeline.h"
#include "nodes/eval/vertex_quality.h"
#include "nodes/io/mesh_readers.h"
#include "nodes/io/mesh_writers.h"
#include "nodes/io/parse_util.h"
#include "nodes/io/read_point_cloud.h"
#include "options/eval_report.h"
#include "runtime/error.h"
#include "runtime/threads.h"

namespace meshflow::python {

namespace {

// Optional (n, 3) normals; ValueError for another row count (`items`: "points", "vertices").
std::vector<Eigen::Vector3f> normal_rows(const py::object& normals, std::size_t n,
                                         const char* items) {
  if (normals.is_none()) return {};
  std::vector<Eigen::Vector3f> rows =
      copy_rows<Eigen::Vector3f>(rows_of_three<float>(normals, "normals"));
  if (rows.size() != n)
    throw py::value_error("normals: " + std::to_string(rows.size()) + " rows for " +
                          std::to_string(n) + " " + items);
  return rows;
}

// Optional (n, 3) colours 0-255; ValueError for floats, values outside 0-255 or another row
// count.
std::vector<Rgb8> color_rows(const py::object& colors, std::size_t n, const char* items) {
  if (colors.is_none()) return {};
  // Float colours are usually in [0, 1]: a cast to uint8 would turn them into 0 and 1.
  const py::array given = py::array::ensure(colors);
  if (given && given.dtype().kind() == 'f')
    throw py::value_error("colors: expected integers 0-255 (uint8), got " +
                          std::string(py::str(given.dtype())) +
                          " (multiply colours in [0, 1] by 255)");
  // Read wide, so that 256 or -1 is an error instead of wrapping round.
  const auto wide = rows_of_three<std::int64_t>(colors, "colors");
  std::vector<Rgb8> rows(static_cast<std::size_t>(wide.shape(0)));
  const std::int64_t* v = wide.data();
  for (std::size_t i = 0; i < rows.size(); ++i, v += 3) {
    if (std::min({v[0], v[1], v[2]}) < 0 || std::max({v[0], v[1], v[2]}) > 255)
      throw py::value_error("colors: row " + std::to_string(i) + " has a value outside 0-255");
    rows[i] = {static_cast<std::uint8_t>(v[0]), static_cast<std::uint8_t>(v[1]),
               static_cast<std::uint8_t>(v[2])};
  }
  if (rows.size() != n)
    throw py::value_error("colors: " + std::to_string(rows.size()) + " rows for " +
                          std::to_string(n) + " " + items);
  return rows;
}

}  // namespace

Cloud make_cloud(const py::handle& points, const py::object& normals, const py::object& colors,
                 const py::object& sensor_origin) {
  Cloud cloud;
  PointCloud& c = *cloud.data;
  c.positions = copy_rows<Eigen::Vector3f>(rows_of_three<float>(points, "points"));
  const std::size_t n = c.positions.size();
  c.normals = normal_rows(normals, n, "points");
  c.colors = color_rows(colors, n, "points");
  if (!sensor_origin.is_none()) {
    const auto s = sensor_origin.cast<std::vector<float>>();
    if (s.size() != 3 || !std::isfinite(s[0]) || !std::isfinite(s[1]) || !std::isfinite(s[2]))
      throw py::value_error("sensor_origin: expected three finite numbers (x, y, z in metres)");
    c.sensor_origin = {s[0], s[1], s[2]};
    c.has_sensor_origin = true;
  }
  return cloud;
}

Mesh make_mesh(const py::handle& vertices, const py::handle& triangles, const py::object& normals,
               const py::object& colors) {
  Mesh mesh;
  TriangleMesh& m = *mesh.data;
  m.vertices = copy_rows<Eigen::Vector3f>(rows_of_three<float>(vertices, "vertices"));
  const std::size_t n = m.vertices.size();
  for (std::size_t i = 0; i < n; ++i)
    if (!m.vertices[i].allFinite())
      throw py::value_error("vertices: row " + std::to_string(i) + " is not finite");
  // Read wide, so that -1 or 2^32 is an error instead of wrapping round.
  const auto wide = rows_of_three<std::int64_t>(triangles, "triangles");
  m.triangles.resize(static_cast<std::size_t>(wide.shape(0)));
  const std::int64_t* t = wide.data();
  for (std::size_t i = 0; i < m.triangles.size(); ++i, t += 3) {
    for (int k = 0; k < 3; ++k) {
      if (t[k] < 0 || static_cast<std::uint64_t>(t[k]) >= n)
        throw py::value_error("triangles: row " + std::to_string(i) + " refers to vertex " +
                              std::to_string(t[k]) + " of " + std::to_string(n));
      m.triangles[i][k] = static_cast<std::uint32_t>(t[k]);
    }
  }
  m.normals = normal_rows(normals, n, "vertices");
  m.colors = color_rows(colors, n, "vertices");
  return mesh;
}

namespace {

// reconstruct(): a Cloud, or points with optional normals and colours, through the CLI's
// pipeline with the CLI's option names.
Mesh reconstruct(const py::object& input, const py::object& normals, const py::object& colors,
                 const options::PipelineOptions& options) {
  const Cloud cloud = py::isinstance<Cloud>(input) ? input.cast<Cloud>()
                                                   : make_cloud(input, normals, colors, py::none());
  if (py::isinstance<Cloud>(input) && !(normals.is_none() && colors.is_none()))
    throw py::value_error("normals and colors are given with a points array, not with a Cloud");
  ReconstructionConfig config;
  try {
    config = options.config();
  } catch (const Error& e) {  // checked when set; kept for a value changed since
    throw py::value_error(e.what());
  }
  FramePtr frame;
  {
    py::gil_scoped_release no_gil;  // Python threads run while the graph works
    ThreadLimit limit(options.threads);
    ReconstructionPipeline pipeline(config, 1);
    frame = pipeline.reconstruct(*cloud.data, "array");
  }
  // An empty surface fails the extract or optimize stage, as on the CLI and in Pipeline.
  // frame->error names the input and the stage already ("array: extract: ...").
  if (!frame->ok()) throw Error("reconstruct", "", frame->error);
  Mesh mesh;
  *mesh.data = std::move(frame->mesh);
  mesh.origin = frame->origin;
  return mesh;
}

// A reference for evaluate(): a Mesh, a Cloud (its points and normals) or a file eval reads.
TriangleMesh reference_mesh(const py::object& reference, std::string& name) {
  if (py::isinstance<Mesh>(reference)) {
    name = "mesh";
    return *reference.cast<Mesh>().data;
  }
  if (py::isinstance<Cloud>(reference)) {
    name = "cloud";
    const PointCloud& cloud = *reference.cast<Cloud>().data;
    TriangleMesh points;
    points.vertices = cloud.positions;
    points.normals = cloud.normals;
    return points;
  }
  if (py::isinstance<py::str>(reference)) {
    name = reference.cast<std::string>();
    return options::read_reference(name);
  }
  throw py::value_error("reference: expected a Mesh, a Cloud or a file path");
}

}  // namespace
}  // namespace meshflow::python

PYBIND11_MODULE(meshflow, m) {
  using namespace meshflow;
  using namespace meshflow::python;
  m.doc() = "meshflow: surface reconstruction from point clouds and depth images";
  m.attr("__version__") = MESHFLOW_VERSION;
  py::register_exception<Error>(m, "Error", PyExc_RuntimeError);

  py::class_<Cloud>(m, "Cloud", "A point cloud: points in metres, optional normals and colours.")
      .def(py::init(&make_cloud), py::arg("points"), py::arg("normals") = py::none(),
           py::arg("colors") = py::none(), py::arg("sensor_origin") = py::none(),
           "Copies (n, 3) arrays: points and normals as float32, colours as uint8.")
      .def_property_readonly(
          "points",
          [](py::object self) {
            return view<float>(self.cast<Cloud&>().data->positions, 3, self, false);
          },
          "(n, 3) float32 view, metres")
      .def_property_readonly(
          "normals",
          [](py::object self) {
            return view<float>(self.cast<Cloud&>().data->normals, 3, self, true);
          },
          "(n, 3) float32 view or None")
      .def_property_readonly(
          "colors",
          [](py::object self) {
            return view<std::uint8_t>(self.cast<Cloud&>().data->colors, 3, self, true);
          },
          "(n, 3) uint8 view or None")
      .def_property_readonly("sensor_origin",
                             [](const Cloud& c) -> py::object {
                               if (!c.data->has_sensor_origin) return py::none();
                               const Eigen::Vector3f& s = c.data->sensor_origin;
                               return py::make_tuple(s.x(), s.y(), s.z());
                             })
      .def("__len__", [](const Cloud& c) { return c.data->size(); })
      .def("__repr__", [](const Cloud& c) {
        return "<meshflow.Cloud " + std::to_string(c.data->size()) + " points" +
               (c.data->has_normals() ? ", normals" : "") +
               (c.data->has_colors() ? ", colors" : "") + ">";
      });

  py::class_<Mesh>(m, "Mesh", "A triangle mesh: vertices in metres, triangles as vertex indices.")
      .def(py::init([](const py::handle& vertices, const py::handle& triangles,
                       const py::object& normals, const py::object& colors) {
             return make_mesh(vertices, triangles, normals, colors);
           }),
           py::arg("vertices"), py::arg("triangles"), py::arg("normals") = py::none(),
           py::arg("colors") = py::none(),
           "A mesh from arrays (e.g. an Open3D mesh's np.asarray(vertices), "
           "np.asarray(triangles)): vertices (v, 3) metres, triangles (t, 3) vertex indices, "
           "optional normals (v, 3) and colours (v, 3) 0-255; copied. ValueError naming the "
           "array for a wrong shape, a non-finite vertex or an index out of range.")
      .def_property_readonly(
          "vertices",
          [](py::object self) {
            return view<float>(self.cast<Mesh&>().data->vertices, 3, self, false);
          },
          "(v, 3) float32 view, metres")
      .def_property_readonly(
          "triangles",
          [](py::object self) {
            return view<std::uint32_t>(self.cast<Mesh&>().data->triangles, 3, self, false);
          },
          "(t, 3) uint32 view, counter-clockwise seen from outside")
      .def_property_readonly(
          "normals",
          [](py::object self) {
            return view<float>(self.cast<Mesh&>().data->normals, 3, self, true);
          },
          "(v, 3) float32 view or None")
      .def_property_readonly(
          "colors",
          [](py::object self) {
            return view<std::uint8_t>(self.cast<Mesh&>().data->colors, 3, self, true);
          },
          "(v, 3) uint8 view or None")
      .def_property_readonly("origin",
                             [](const Mesh& mesh) {
                               return py::make_tuple(mesh.origin.x(), mesh.origin.y(),
                                                     mesh.origin.z());
                             })
      .def(
          "write",
          [](const Mesh& mesh, const std::string& path, const py::object& quality,
             const py::object& observations) {
            std::vector<io::VertexScalar> scalars;
            const auto add = [&](const std::string& name, const py::object& values) {
              if (values.is_none()) return;
              if (io::lower_extension(path) != ".ply")
                throw py::value_error(name + ": a PLY vertex property; give a .ply path");
              const auto q =
                  py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(values);
              if (!q || q.ndim() != 1 ||
                  static_cast<std::size_t>(q.shape(0)) != mesh.data->vertices.size())
                throw py::value_error(name + ": expected one number per vertex (" +
                                      std::to_string(mesh.data->vertices.size()) + ")");
              scalars.push_back({name, std::vector<float>(q.data(), q.data() + q.shape(0))});
            };
            add("quality", quality);
            add("observations", observations);
            py::gil_scoped_release no_gil;
            if (scalars.empty()) return io::write_mesh(path, *mesh.data, mesh.origin);
            io::write_ply(path, *mesh.data, io::PlyEncoding::kBinary, mesh.origin, scalars);
          },
          py::arg("path"), py::arg("quality") = py::none(), py::arg("observations") = py::none(),
          "Writes .ply, .obj, .stl, .off or .glb by extension; quality, observations: optional "
          "(v,) floats written as the PLY vertex properties of those names (e.g. "
          "vertex_quality(mesh, cloud), vertex_observations(mesh, cloud, voxel)).")
      .def("__repr__", [](const Mesh& mesh) {
        return "<meshflow.Mesh " + std::to_string(mesh.data->vertices.size()) + " vertices, " +
               std::to_string(mesh.data->triangles.size()) + " triangles>";
      });

  m.def(
      "read_cloud",
      [](const std::string& path, const std::string& columns) {
        Cloud cloud;
        py::gil_scoped_release no_gil;
        *cloud.data = io::read_point_cloud(path, columns);
        return cloud;
      },
      py::arg("path"), py::arg("columns") = "",
      "Reads PLY, PCD, XYZ/TXT/PTS/CSV, 3DTK .3d (+ .pose) or LAS by extension.");

  m.def(
      "read_mesh",
      [](const std::string& path) {
        Mesh mesh;
        py::gil_scoped_release no_gil;
        *mesh.data = io::read_mesh(path);
        return mesh;
      },
      py::arg("path"), "Reads a PLY, OBJ, OFF, STL or glTF binary (.glb) mesh by extension.");

  // The mesh's vertices in the cloud's frame (each may be georeferenced: a local frame at its
  // own origin, or world coordinates), and the cloud.
  struct VerticesAndPoints {
    std::vector<Eigen::Vector3f> vertices;
    PointCloud cloud;
  };
  const auto in_one_frame = [](const Mesh& mesh, const py::object& points) {
    VerticesAndPoints out;
    out.cloud = py::isinstance<Cloud>(points)
                    ? *points.cast<Cloud>().data
                    : *make_cloud(points, py::none(), py::none(), py::none()).data;
    out.vertices = mesh.data->vertices;
    const Eigen::Vector3d shift = mesh.origin - out.cloud.origin;
    if (!shift.isZero())
      for (Eigen::Vector3f& v : out.vertices) v = (v.cast<double>() + shift).cast<float>();
    return out;
  };
  const auto as_array = [](const std::vector<float>& values) {
    py::array_t<float> out(static_cast<py::ssize_t>(values.size()));
    std::copy(values.begin(), values.end(), out.mutable_data());
    return out;
  };

  m.def(
      "vertex_quality",
      [in_one_frame, as_array](const Mesh& mesh, const py::object& points) {
        const VerticesAndPoints both = in_one_frame(mesh, points);
        std::vector<float> d;
        {
          py::gil_scoped_release no_gil;
          d = nearest_point_distances(both.vertices, both.cloud.positions);
        }
        return as_array(d);
      },
      py::arg("mesh"), py::arg("points"),
      R"(Each vertex's distance in metres to the nearest of `points` (a Cloud or (n, 3) array,
e.g. the cloud the mesh was made from; georeferenced ones compared in one frame), as a (v,)
float32 array: what reconstruct --quality writes. Exact (kd-tree); parallel, the GIL released.)");

  m.def(
      "vertex_observations",
      [in_one_frame, as_array](const Mesh& mesh, const py::object& points, float radius) {
        const VerticesAndPoints both = in_one_frame(mesh, points);
        VertexSupport support;
        {
          py::gil_scoped_release no_gil;
          support = vertex_support(both.vertices, both.cloud.positions, radius);
        }
        return as_array(support.observations);
      },
      py::arg("mesh"), py::arg("points"), py::arg("radius"),
      R"(For each vertex, how many of `points` (a Cloud or (n, 3) array) lie within `radius`
metres, as a (v,) float32 array: reconstruct --quality writes it as 'observations' with the voxel
size as the radius. Exact (kd-tree); parallel, the GIL released. meshflow.Error on a radius
<= 0.)");

  m.def(
      "evaluate",
      [](const Mesh& mesh, const py::object& reference, float wall_radius) {
        std::string name;
        const TriangleMesh ref = reference_mesh(reference, name);
        std::string json;
        {
          py::gil_scoped_release no_gil;
          json = options::reference_evaluation_json(
                     options::evaluate_reference(*mesh.data, ref, wall_radius), "mesh", name)
                     .dump();
        }
        return py::module_::import("json").attr("loads")(json);
      },
      py::arg("mesh"), py::arg("reference"), py::arg("wall_radius") = 0.0f,
      R"(The figures of `meshflow eval MESH --reference REF --json`, as a dict: distances both
ways (mean, rms, median, p95, max in metres), normal deviation, inside-out share, topology,
orientation, double walls. reference: a Mesh, a Cloud or a file path.)");

  bind_depth(m);
  bind_readers(m);
  bind_live(m);
  bind_compress(m);
#ifdef MESHFLOW_WITH_SERVE
  bind_serve(m);
#endif

  static const std::string reconstruct_doc =
      R"(Reconstructs a surface from a Cloud or an (n, 3) points array (with optional (n, 3)
normals and uint8 colours). Keyword arguments are )" +
      option_list() + R"( (--normals is normal_source; voxel 0 chooses 3x the median point
spacing). The GIL is released while the pipeline runs. Raises meshflow.Error for input the
pipeline cannot mesh, ValueError for malformed arrays or settings, TypeError for an unknown
keyword.)";
  m.def(
      "reconstruct",
      [](const py::object& input, const py::object& normals, const py::object& colors,
         const py::kwargs& options) {
        return reconstruct(input, normals, colors, pipeline_options(options));
      },
      py::arg("cloud"), py::arg("normals") = py::none(), py::arg("colors") = py::none(),
      reconstruct_doc.c_str());
}
