// The TSDF map file (run --fuse --save-map / --load-map). Each input's checksum is recomputed
// before it is read (inputs of 16 bytes and more): the checksum would otherwise reject nearly
// every mutation before the fields behind it are parsed. A wrong checksum is the reader tests'
// case (TsdfMapFile.*).
#include <vector>

#include "fuzz_file.h"
#include "nodes/fusion/tsdf_map_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::uint8_t> bytes(data, data + size);
  if (bytes.size() >= 16) meshflow::reseal_tsdf_map(bytes.data(), bytes.size());
  meshflow::fuzz::read_as(bytes.data(), bytes.size(), ".tsdf",
                          [](const std::string& p) { meshflow::read_tsdf_map(p); });
  return 0;
}
