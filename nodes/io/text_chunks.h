#pragma once
// Parallel parsing of line-oriented text files: the file is read once, split at line ends into
// chunks, and the chunks are parsed concurrently and joined in file order.

#include <cstddef>
#include <exception>
#include <string>
#include <string_view>
#include <vector>

#include <tbb/parallel_for.h>

namespace meshflow::io {

struct TextChunk {
  std::string_view text;   ///< whole lines (the last may lack its '\n')
  std::size_t first_line;  ///< 1-based line number of the chunk's first line
};

/// The file's bytes; throws meshflow::Error if it cannot be opened or read.
std::string read_whole_file(const std::string& path);

/// Splits `text` into chunks of about `chunk_bytes` that end at line ends, each with its first
/// line's number (the chunks' lines counted in parallel). O(n).
std::vector<TextChunk> split_into_line_chunks(std::string_view text,
                                              std::size_t chunk_bytes = 1 << 18);

/// Calls parse(chunk, result) for every chunk in parallel and returns the results in chunk
/// order. If chunks throw, the exception of the earliest such chunk is rethrown, so the error
/// reported for a file does not depend on scheduling.
template <typename Result, typename Parse>
std::vector<Result> parse_chunks(const std::vector<TextChunk>& chunks, Parse parse) {
  std::vector<Result> results(chunks.size());
  std::vector<std::exception_ptr> errors(chunks.size());
  tbb::parallel_for(std::size_t{0}, chunks.size(), [&](std::size_t i) {
    try {
      parse(chunks[i], results[i]);
    } catch (...) {
      errors[i] = std::current_exception();
    }
  });
  for (const auto& e : errors) {
    if (e) std::rethrow_exception(e);
  }
  return results;
}

}  // namespace meshflow::io
