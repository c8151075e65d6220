#include "tools/cli_checks.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <unistd.h>

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

namespace {

std::string byte_size_expected(const std::string& text) {
  return "expected a size such as 512M, 4G or 0 (no limit), got '" + text + "'";
}

}  // namespace

std::size_t parse_byte_size(const std::string& text, const std::string& option) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  const std::string suffix(end == nullptr ? "" : end);
  double scale = 0.0;
  if (suffix.empty() || suffix == "B") scale = 1.0;
  if (suffix == "K" || suffix == "k") scale = 1024.0;
  if (suffix == "M" || suffix == "m") scale = 1024.0 * 1024.0;
  if (suffix == "G" || suffix == "g") scale = 1024.0 * 1024.0 * 1024.0;
  if (suffix == "T" || suffix == "t") scale = 1024.0 * 1024.0 * 1024.0 * 1024.0;
  const double bytes = value * scale;
  if (end == text.c_str() || scale == 0.0 || !std::isfinite(bytes) || bytes < 0.0 || bytes > 1e18)
    throw CLI::ValidationError(option, byte_size_expected(text));
  return static_cast<std::size_t>(bytes);
}

CLI::Validator byte_size() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        try {
          parse_byte_size(text, "");
          return "";
        } catch (const CLI::ValidationError&) {
          return byte_size_expected(text);
        }
      },
      "SIZE");
}

std::size_t default_memory_limit() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  if (pages <= 0 || page <= 0) return 0;
  return static_cast<std::size_t>(pages) / 5 * 4 * static_cast<std::size_t>(page);
}

}  // namespace meshflow::cli
