#include "tools/cli_checks.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace meshflow::cli {

CLI::Validator number_in(double low, double high, bool low_open) {
  char range[80];
  std::snprintf(range, sizeof range, "%c%g, %g]", low_open ? '(' : '[', low, high);
  const std::string expected = std::string("a number in ") + range;
  return CLI::Validator(
      [low, high, low_open, expected](std::string& text) -> std::string {
        char* end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        const bool parsed = !text.empty() && end == text.c_str() + text.size();
        const bool inside =
            std::isfinite(value) && (low_open ? value > low : value >= low) && value <= high;
        if (parsed && inside) return {};
        return "expected " + expected + ", got '" + text + "'";
      },
      expected);
}

}  // namespace meshflow::cli
