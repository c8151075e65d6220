// PLY point clouds and meshes (ascii, binary little and big endian).
#include "fuzz_file.h"
#include "nodes/io/ply_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  meshflow::fuzz::read_as(data, size, ".ply",
                          [](const std::string& p) { meshflow::io::read_ply(p); });
  meshflow::fuzz::read_as(data, size, ".ply",
                          [](const std::string& p) { meshflow::io::read_ply_mesh(p); });
  return 0;
}
