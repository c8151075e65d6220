#include "nodes/io/text_chunks.h"

#include <algorithm>
#include <fstream>

#include "nodes/io/parse_util.h"
#include "runtime/error.h"

namespace meshflow::io {

std::string read_whole_file(const std::string& path) {
  std::ifstream in = open_input(path);
  std::string data;
  data.resize(file_size(path));
  in.read(data.data(), static_cast<std::streamsize>(data.size()));
  if (static_cast<std::size_t>(in.gcount()) != data.size()) throw Error(path, "", "read failed");
  return data;
}

std::vector<TextChunk> split_into_line_chunks(std::string_view text, std::size_t chunk_bytes) {
  std::vector<TextChunk> chunks;
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = std::min(text.size(), start + std::max<std::size_t>(chunk_bytes, 1));
    if (end < text.size()) {
      const std::size_t nl = text.find('\n', end);
      end = nl == std::string_view::npos ? text.size() : nl + 1;
    }
    chunks.push_back({text.substr(start, end - start), 0});
    start = end;
  }
  // Each chunk's line count in parallel (a scan of every byte), then the first lines in order.
  std::vector<std::size_t> lines(chunks.size());
  tbb::parallel_for(std::size_t{0}, chunks.size(), [&](std::size_t c) {
    lines[c] =
        static_cast<std::size_t>(std::count(chunks[c].text.begin(), chunks[c].text.end(), '\n'));
  });
  std::size_t line = 1;
  for (std::size_t c = 0; c < chunks.size(); ++c) {
    chunks[c].first_line = line;
    line += lines[c];
  }
  return chunks;
}

}  // namespace meshflow::io
