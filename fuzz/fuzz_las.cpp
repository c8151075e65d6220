// LAS 1.2-1.4 point formats 0-3 and 6-8.
#include "fuzz_file.h"
#include "nodes/io/las_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  meshflow::fuzz::read_as(data, size, ".las",
                          [](const std::string& p) { meshflow::io::read_las(p); });
  return 0;
}
