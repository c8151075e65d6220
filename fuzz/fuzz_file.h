#pragma once
// Shared by the libFuzzer targets: meshflow's readers take paths, so each input is written to a
// file of this process (in /dev/shm when it exists: memory, not disk) and read back. A reader
// may throw meshflow::Error for bad input, nothing else: any other exception escapes and
// libFuzzer reports it, as it reports crashes, sanitizer findings, leaks, and allocations past
// -malloc_limit_mb (a header that makes a reader allocate more than the file can hold).

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

#include "runtime/error.h"

namespace meshflow::fuzz {

/// This process's scratch path with `suffix` appended (in /dev/shm when it exists).
inline std::string scratch_path(const std::string& suffix) {
  static const std::string dir = std::filesystem::is_directory("/dev/shm")
                                     ? std::string("/dev/shm")
                                     : std::filesystem::temp_directory_path().string();
  return dir + "/meshflow_fuzz_" + std::to_string(::getpid()) + suffix;
}

/// Writes data[0, size) to `path` (replacing it).
inline void write_file(const std::string& path, const std::uint8_t* data, std::size_t size) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) __builtin_trap();  // the harness itself failed
  if (size > 0 && std::fwrite(data, 1, size, f) != size) __builtin_trap();
  std::fclose(f);
}

/// Writes data[0, size) to this process's file with extension `ext` (".ply") and returns its
/// path; the same path for every input of a run.
inline std::string write_input(const std::uint8_t* data, std::size_t size, const std::string& ext) {
  const std::string path = scratch_path(ext);
  write_file(path, data, size);
  return path;
}

/// Runs read(path) on the input written as a file with extension `ext`; meshflow::Error is the
/// expected outcome of bad input and is swallowed.
template <typename Read>
void read_as(const std::uint8_t* data, std::size_t size, const std::string& ext, Read read) {
  const std::string path = write_input(data, size, ext);
  try {
    read(path);
  } catch (const Error&) {
  }
}

}  // namespace meshflow::fuzz
