#pragma once
// The option model's checks as CLI11 validators, for any of the model's tables
// (options/pipeline_options.h, options/serve_options.h): a usage error (exit 2) with the model's
// message, when the command line is parsed.

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdlib>
#include <limits>
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
          if constexpr (!std::is_floating_point_v<T>) {
            // Compared before the cast: converting an out-of-range double is undefined.
            // 2^digits is exact in a double and one past the type's largest value.
            const double past_max = std::ldexp(1.0, std::numeric_limits<T>::digits);
            if (value < static_cast<double>(std::numeric_limits<T>::min()) || value >= past_max)
              return "expected a whole number in range, got '" + text + "'";
          }
          probe.*member = static_cast<T>(value);
        }
        return spec.check(probe);
      },
      "");
}

}  // namespace meshflow::cli
