// The option model (options/pipeline_options.h) as Python keyword arguments: reconstruct() and
// Pipeline() accept every option `meshflow reconstruct` has, under its name (dashes as
// underscores; --normals is normal_source, the normals argument being the array), with its
// default, checked by the same checks with the same messages.

#include <pybind11/stl.h>

#include <cstdio>
#include <limits>
#include <string>
#include <type_traits>
#include <variant>

#include "python/bindings.h"

namespace meshflow::python {
namespace {

using options::OptionSpec;
using options::PipelineOptions;

const OptionSpec* find_spec(const std::string& name) {
  for (const OptionSpec& spec : options::pipeline_option_specs())
    if (options::python_name(spec) == name) return &spec;
  return nullptr;
}

// Stores `value` in the spec's field of `o`: TypeError for a value of another type, ValueError
// with the model's message for one that fails the check.
void set_option(const OptionSpec& spec, PipelineOptions& o, const py::handle& value) {
  const std::string name = options::python_name(spec);
  if (name == "crop" && !py::isinstance<py::str>(value) && py::isinstance<py::sequence>(value)) {
    // crop=(minx, miny, minz, maxx, maxy, maxz): the model's text, checked there.
    std::string text;
    for (const py::handle item : value) {
      if (!py::isinstance<py::float_>(item) && !py::isinstance<py::int_>(item))
        throw py::type_error("crop: expected six numbers, got " + std::string(py::repr(value)));
      char number[40];
      std::snprintf(number, sizeof number, "%.9g", item.cast<double>());
      text += (text.empty() ? "" : ",") + std::string(number);
    }
    return set_option(spec, o, py::str(text));
  }
  std::visit(
      [&](auto member) {
        using T = std::remove_reference_t<decltype(o.*member)>;
        // bool and str only from their own types; numbers from ints and floats (not bools).
        const bool right_type =
            std::is_same_v<T, bool>          ? py::isinstance<py::bool_>(value)
            : std::is_same_v<T, std::string> ? py::isinstance<py::str>(value)
            : std::is_floating_point_v<T>
                ? (py::isinstance<py::float_>(value) || py::isinstance<py::int_>(value)) &&
                      !py::isinstance<py::bool_>(value)
                : py::isinstance<py::int_>(value) && !py::isinstance<py::bool_>(value);
        if (!right_type)
          throw py::type_error(name + ": expected a value like " +
                               std::string(py::repr(py::cast(PipelineOptions{}.*member))) +
                               ", got " + std::string(py::repr(value)));
        if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) {
          // Range first: a negative count or one past the type is the model's error, not a cast's.
          const auto wide = value.cast<long long>();
          if (wide < 0 && std::is_unsigned_v<T>)
            throw py::value_error(name + ": expected a whole number >= 0, got " +
                                  std::to_string(wide));
          if (static_cast<long double>(wide) >
                  static_cast<long double>(std::numeric_limits<T>::max()) ||
              (std::is_signed_v<T> && wide < static_cast<long long>(std::numeric_limits<T>::min())))
            throw py::value_error(name + ": expected a whole number in range, got " +
                                  std::to_string(wide));
          o.*member = static_cast<T>(wide);
        } else {
          o.*member = value.cast<T>();
        }
      },
      spec.field);
  const std::string problem = spec.check(o);
  if (!problem.empty()) throw py::value_error(name + ": " + problem);
}

}  // namespace

PipelineOptions pipeline_options(const py::kwargs& kwargs) {
  PipelineOptions o;
  for (const auto& [key, value] : kwargs) {
    const std::string name = py::str(key);
    const OptionSpec* spec = find_spec(name);
    if (spec == nullptr)
      throw py::type_error("unexpected keyword argument '" + name + "'; " + option_list());
    set_option(*spec, o, value);
  }
  return o;
}

std::string option_list() {
  const PipelineOptions defaults;
  std::string out = "the CLI's options, with its defaults:";
  const char* separator = " ";
  for (const OptionSpec& spec : options::pipeline_option_specs()) {
    const std::string value = std::visit(
        [&](auto member) { return std::string(py::repr(py::cast(defaults.*member))); }, spec.field);
    out += separator + options::python_name(spec) + "=" + value;
    separator = ", ";
  }
  return out;
}

}  // namespace meshflow::python
