// The CLI's pipeline options as Python keyword arguments: one table, so reconstruct() and
// Pipeline() accept every option `meshflow reconstruct` has, under its name (dashes as
// underscores; --normals is normal_source, the normals argument being the array), with its
// default.

#include <pybind11/stl.h>

#include <functional>
#include <string>
#include <vector>

#include "python/bindings.h"

namespace meshflow::python {
namespace {

struct Option {
  const char* name;
  std::function<void(cli::PipelineOptions&, const py::handle&)> set;
  std::function<py::object(const cli::PipelineOptions&)> get;
};

template <typename T>
Option option(const char* name, T cli::PipelineOptions::*member) {
  return {name,
          [member, name](cli::PipelineOptions& o, const py::handle& value) {
            try {
              o.*member = value.cast<T>();
            } catch (const py::cast_error&) {
              throw py::type_error(std::string(name) + ": expected a value like " +
                                   std::string(py::repr(py::cast(cli::PipelineOptions{}.*member))) +
                                   ", got " + std::string(py::repr(value)));
            }
          },
          [member](const cli::PipelineOptions& o) { return py::cast(o.*member); }};
}

const std::vector<Option>& options() {
  using O = cli::PipelineOptions;
  static const std::vector<Option> table = {
      option("voxel", &O::voxel),
      option("kn", &O::kn),
      option("ki", &O::ki),
      option("kd", &O::kd),
      option("threads", &O::threads),
      option("adaptive_k", &O::adaptive_k),
      option("max_distance", &O::max_distance),
      option("max_disagreement", &O::max_disagreement),
      option("max_extrapolation", &O::max_extrapolation),
      option("min_component", &O::min_component),
      option("filter_voxel", &O::filter_voxel),
      option("outlier_k", &O::outlier_k),
      option("min_range", &O::min_range),
      option("max_range", &O::max_range),
      option("extract", &O::extract),
      option("optimize", &O::optimize),
      option("max_hole", &O::max_hole),
      option("decimate_to", &O::decimate_to),
      option("contour_tolerance", &O::contour_tolerance),
      option("max_projection", &O::max_projection),
      option("plane_tolerance", &O::plane_tolerance),
      option("max_rim", &O::max_rim),
      option("remesh_tolerance", &O::remesh_tolerance),
      option("organized_as_depth", &O::organized_as_depth),
      option("normal_source", &O::normals),
      option("orient", &O::orient),
      option("max_memory", &O::max_memory),
  };
  return table;
}

}  // namespace

cli::PipelineOptions pipeline_options(const py::kwargs& kwargs) {
  cli::PipelineOptions o;
  for (const auto& [key, value] : kwargs) {
    const std::string name = py::str(key);
    const Option* found = nullptr;
    for (const Option& candidate : options())
      if (name == candidate.name) found = &candidate;
    if (found == nullptr)
      throw py::type_error("unexpected keyword argument '" + name + "'; " + option_list());
    found->set(o, value);
  }
  return o;
}

std::string option_list() {
  const cli::PipelineOptions defaults;
  std::string out = "the CLI's options, with its defaults:";
  const char* separator = " ";
  for (const Option& option : options()) {
    out += separator + std::string(option.name) + "=" + std::string(py::repr(option.get(defaults)));
    separator = ", ";
  }
  return out;
}

}  // namespace meshflow::python
