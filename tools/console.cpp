#include "tools/console.h"

#include <unistd.h>

#include <cstdarg>
#include <cstdio>

namespace meshflow::cli {

ConsoleOptions& console() {
  static ConsoleOptions options;
  return options;
}

void add_console_flags(CLI::App* cmd, bool json) {
  ConsoleOptions& o = console();
  auto* quiet = cmd->add_flag("-q,--quiet", o.quiet, "Print nothing on success");
  cmd->add_flag("-v,--verbose", o.verbose, "Also print the settings used and per-frame lines")
      ->excludes(quiet);
  cmd->add_flag("--progress", o.progress,
                "Progress lines on stderr even when it is not a terminal (steps over a second)");
  if (json)
    cmd->add_flag("--json", o.json, "Print one JSON document on stdout instead of the report");
}

namespace {
void vprint(const char* format, va_list args) { std::vfprintf(stdout, format, args); }
}  // namespace

void report(const char* format, ...) {
  if (console().quiet || console().json) return;
  va_list args;
  va_start(args, format);
  vprint(format, args);
  va_end(args);
}

void detail(const char* format, ...) {
  if (!console().verbose || console().json) return;
  va_list args;
  va_start(args, format);
  vprint(format, args);
  va_end(args);
}

bool progress_enabled() {
  if (console().progress) return true;
  if (console().quiet || console().json) return false;
  return ::isatty(::fileno(stderr)) != 0;
}

void print_json(const nlohmann::json& doc) { std::printf("%s\n", doc.dump(2).c_str()); }

}  // namespace meshflow::cli
