// PCD point clouds: ascii, binary and binary_compressed (LZF).
#include "fuzz_file.h"
#include "nodes/io/pcd_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  meshflow::fuzz::read_as(data, size, ".pcd",
                          [](const std::string& p) { meshflow::io::read_pcd(p); });
  return 0;
}
