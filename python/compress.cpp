// meshflow.compress / meshflow.decompress: meshes to and from .mfc bytes (nodes/compress).

#include <limits>

#include "bindings.h"
#include "nodes/compress/compressed_mesh.h"
#include "nodes/compress/progressive_mesh.h"
#include "options/pipeline_options.h"

namespace meshflow::python {

void bind_compress(py::module_& m) {
  m.def(
      "compress",
      [](const Mesh& mesh, bool progressive, unsigned bits, double step, bool normals, bool colors,
         int normal_bits, double normal_error) {
        options::PipelineOptions model;
        model.normal_bits = normal_bits;
        model.normal_error = static_cast<float>(normal_error);
        for (const char* name : {"normal-bits", "normal-error"}) {
          const options::OptionSpec& spec = options::option_spec(name);
          const std::string problem = spec.check(model);
          if (!problem.empty()) throw py::value_error(options::python_name(spec) + ": " + problem);
        }
        compress::CompressConfig config;
        config.normal_bits = static_cast<unsigned>(normal_bits);
        config.normal_error = static_cast<double>(model.normal_error);
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
      py::arg("normal_bits") = static_cast<int>(compress::kDefaultNormalBits),
      py::arg("normal_error") = 0.0,
      R"(The mesh as compressed-mesh bytes (the .mfc format): Edgebreaker, or with
progressive=True a base mesh and vertex splits. bits (1..30) or step (metres) set the position
quantisation (default: 1/64 of the median edge). normal_bits (4..20, default 10: within 0.25
degrees, doubling per bit fewer) sets the normals' precision, or normal_error (degrees, 0.001..30)
the largest angle between an input normal and its decoded one; normal_bits=0 stores none and the
decoder recomputes them from the decoded geometry. Positions are stored in world coordinates (the mesh's origin
added).)");

  m.def(
      "decompress",
      [](const py::bytes& data, py::object splits, py::object triangles, bool partial) {
        const std::string_view view = data;
        const std::vector<unsigned char> bytes(view.begin(), view.end());
        Mesh mesh;
        compress::ProgressiveLevel level;
        if (!splits.is_none()) level.splits = splits.cast<std::size_t>();
        if (!triangles.is_none()) level.triangles = triangles.cast<std::size_t>();
        py::gil_scoped_release no_gil;
        if (partial) {
          *mesh.data = compress::decompress_progressive_prefix(bytes, "bytes", level).mesh;
        } else if (splits.is_none() && triangles.is_none()) {
          *mesh.data = compress::decompress_mesh(bytes, "bytes");
        } else {
          *mesh.data = compress::decompress_progressive_level(bytes, "bytes", level);
        }
        return mesh;
      },
      py::arg("data"), py::arg("splits") = py::none(), py::arg("triangles") = py::none(),
      py::arg("partial") = false,
      R"(A Mesh from compressed-mesh bytes; for a progressive stream, splits=K applies K
vertex splits to the base mesh and triangles=N stops at N triangles (default: the full mesh).
partial=True accepts a prefix of a progressive file ending at a packet boundary (a stream's
first bytes) and decodes the levels it holds, every part's checksum checked.
Raises meshflow.Error naming the field for corrupt or truncated data.)");
}

}  // namespace meshflow::python
