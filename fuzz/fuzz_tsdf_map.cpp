// The TSDF map file (run --fuse --save-map / --load-map).
#include "fuzz_file.h"
#include "nodes/fusion/tsdf_map_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  meshflow::fuzz::read_as(data, size, ".tsdf",
                          [](const std::string& p) { meshflow::read_tsdf_map(p); });
  return 0;
}
