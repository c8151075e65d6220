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
  std::size_t start = 0, line = 1;
  while (start < text.size()) {
    std::size_t end = std::min(text.size(), start + std::max<std::size_t>(chunk_bytes, 1));
    if (end < text.size()) {
      const std::size_t nl = text.find('\n', end);
      end = nl == std::string_view::npos ? text.size() : nl + 1;
    }
    const std::string_view piece = text.substr(start, end - start);
    chunks.push_back({piece, line});
    line += static_cast<std::size_t>(std::count(piece.begin(), piece.end(), '\n'));
    start = end;
  }
  return chunks;
}

}  // namespace meshflow::io
