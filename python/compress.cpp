// meshflow.compress / meshflow.decompress: meshes to and from .mfc bytes (nodes/compress).

#include <limits>

#include "bindings.h"
#include "nodes/compress/compressed_mesh.h"
#include "nodes/compress/progressive_mesh.h"

namespace meshflow::python {

void bind_compress(py::module_& m) {
  m.def(
      "compress",
      [](const Mesh& mesh, bool progressive, unsigned bits, double step, bool normals,
         bool colors) {
        compress::CompressConfig config;
        config.position_bits = bits;
        config.step = step;
        config.normals = normals;
        config.colors = colors;
        config.origin_offset = mesh.origin;
        std::vector<unsigned char> out;
        {
          py::gil_scoped_release no_gil;
          out = progressive ? compress::compress_progressive(*mesh.data, config)
                            : compress::compress_mesh(*mesh.data, config);
        }
        return py::bytes(reinterpret_cast<const char*>(out.data()),
                         static_cast<py::ssize_t>(out.size()));
      },
      py::arg("mesh"), py::arg("progressive") = false, py::arg("bits") = 0u, py::arg("step") = 0.0,
      py::arg("normals") = true, py::arg("colors") = true,
      R"(The mesh as compressed-mesh bytes (the .mfc format): Edgebreaker, or with
progressive=True a base mesh and vertex splits. bits (1..30) or step (metres) set the position
quantisation (default: 1/64 of the median edge). Positions are stored in world coordinates
(the mesh's origin added).)");

  m.def(
      "decompress",
      [](const py::bytes& data, py::object splits, py::object triangles) {
        const std::string_view view = data;
        const std::vector<unsigned char> bytes(view.begin(), view.end());
        Mesh mesh;
        py::gil_scoped_release no_gil;
        if (splits.is_none() && triangles.is_none()) {
          *mesh.data = compress::decompress_mesh(bytes, "bytes");
        } else {
          compress::ProgressiveLevel level;
          {
            py::gil_scoped_acquire gil;
            if (!splits.is_none()) level.splits = splits.cast<std::size_t>();
            if (!triangles.is_none()) level.triangles = triangles.cast<std::size_t>();
          }
          *mesh.data = compress::decompress_progressive_level(bytes, "bytes", level);
        }
        return mesh;
      },
      py::arg("data"), py::arg("splits") = py::none(), py::arg("triangles") = py::none(),
      R"(A Mesh from compressed-mesh bytes; for a progressive stream, splits=K applies K
vertex splits to the base mesh and triangles=N stops at N triangles (default: the full mesh).
Raises meshflow.Error naming the field for corrupt or truncated data.)");
}

}  // namespace meshflow::python
