#pragma once
// What the CLI prints and where: the human report on stdout (silenced by -q, replaced by one
// JSON document with --json), notes and errors on stderr, progress on stderr only on a
// terminal or with --progress. One process runs one command, so the settings are global.

#include <CLI/CLI.hpp>

#include <nlohmann/json.hpp>

namespace meshflow::cli {

struct ConsoleOptions {
  bool quiet = false;     ///< -q: nothing on stdout on success (errors still on stderr)
  bool verbose = false;   ///< -v: the settings used and per-frame lines
  bool json = false;      ///< --json: one JSON document on stdout instead of the report
  bool progress = false;  ///< --progress: progress lines on stderr even when it is not a terminal
};

/// The settings of this process's command (written by the flags add_console_flags registers).
ConsoleOptions& console();

/// Registers -q/--quiet, -v/--verbose and --progress on `cmd`, and --json when `json` is set.
void add_console_flags(CLI::App* cmd, bool json);

/// printf to stdout unless -q or --json is set: the human-readable report.
void report(const char* format, ...) __attribute__((format(printf, 1, 2)));

/// As report(), only with -v.
void detail(const char* format, ...) __attribute__((format(printf, 1, 2)));

/// Whether progress lines go to stderr: always with --progress; otherwise only when stderr is
/// a terminal and neither -q nor --json is set.
bool progress_enabled();

/// Prints `doc` (indented by 2) and a newline to stdout: the --json output.
void print_json(const nlohmann::json& doc);

}  // namespace meshflow::cli
