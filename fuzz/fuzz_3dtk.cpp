// 3DTK scans (scanNNN.3d, centimetres) and their .pose files.
#include "fuzz_file.h"
#include "nodes/io/scan3d_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  meshflow::fuzz::read_as(data, size, ".3d", [](const std::string& p) {
    meshflow::io::read_3dtk_scan(p, meshflow::io::Scan3dOptions{}, "");
  });
  meshflow::fuzz::read_as(data, size, ".pose",
                          [](const std::string& p) { meshflow::io::read_3dtk_pose(p); });
  return 0;
}
