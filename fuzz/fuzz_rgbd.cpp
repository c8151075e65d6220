// RGB-D sequence metadata: Redwood trajectory.log and the camera intrinsics JSON.
#include "fuzz_file.h"
#include "nodes/io/rgbd_sequences.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  meshflow::fuzz::read_as(data, size, ".log",
                          [](const std::string& p) { meshflow::io::read_trajectory_log(p); });
  meshflow::fuzz::read_as(data, size, ".json",
                          [](const std::string& p) { meshflow::io::read_intrinsics_json(p); });
  return 0;
}
