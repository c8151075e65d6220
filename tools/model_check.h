#pragma once
// The option model's checks as CLI11 validators, for any of the model's tables
// (options/pipeline_options.h, options/serve_options.h): a usage error (exit 2) with the model's
// message, when the command line is parsed.

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdlib>
#include <string>
#include <type_traits>

#include "options/pipeline_options.h"

namespace meshflow::cli {

/// A validator that converts the text as CLI11 will, stores it in a default-constructed
/// `Options` and runs `spec`'s check (spec.check(options) -> "" or the problem) on it. Text that
/// is no number of the field's type gets the model's expectation for a number. `spec` must
/// outlive the validator (the model's tables are constants).
template <typename Options, typename Spec, typename T>
CLI::Validator model_check(const Spec& spec, T Options::*member) {
  return CLI::Validator(
      [&spec, member](std::string& text) -> std::string {
        Options probe;
        if constexpr (std::is_same_v<T, std::string>) {
          probe.*member = text;
        } else {
          if constexpr (std::is_unsigned_v<T>) {  // strtoull would wrap "-1"
            if (text.find('-') != std::string::npos)
              return "expected a whole number >= 0, got '" + text + "'";
          }
          char* end = nullptr;
          const double value = std::strtod(text.c_str(), &end);
          if (text.empty() || end != text.c_str() + text.size())
            return "expected a number, got '" + text + "'";
          if (!std::isfinite(value)) return options::check_number(value, 0, 0);
          if (!std::is_floating_point_v<T> && value != std::floor(value))
            return "expected a whole number, got '" + text + "'";
          probe.*member = static_cast<T>(value);
          if (static_cast<double>(probe.*member) != value && !std::is_floating_point_v<T>)
            return "expected a whole number in range, got '" + text + "'";
        }
        return spec.check(probe);
      },
      "");
}

}  // namespace meshflow::cli
