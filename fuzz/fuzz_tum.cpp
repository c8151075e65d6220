// TUM RGB-D association files: the input up to its first zero byte is depth.txt (and rgb.txt),
// the rest groundtruth.txt (the whole input for both when there is no zero byte); the sequence
// is opened and every frame's record built (no images are read).
#include <algorithm>
#include <filesystem>

#include "fuzz_file.h"
#include "nodes/io/rgbd_sequences.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path dir = [] {
    const std::filesystem::path d = meshflow::fuzz::scratch_path("_tum");
    std::filesystem::create_directories(d);
    return d;
  }();
  const std::uint8_t* zero = std::find(data, data + size, std::uint8_t{0});
  const bool split = zero != data + size;
  meshflow::fuzz::write_file((dir / "depth.txt").string(), data,
                             static_cast<std::size_t>(zero - data));
  meshflow::fuzz::write_file((dir / "rgb.txt").string(), data,
                             static_cast<std::size_t>(zero - data));
  if (split)
    meshflow::fuzz::write_file((dir / "groundtruth.txt").string(), zero + 1,
                               static_cast<std::size_t>(data + size - zero - 1));
  else
    meshflow::fuzz::write_file((dir / "groundtruth.txt").string(), data, size);
  try {
    const auto sequence = meshflow::io::open_tum_directory(dir.string());
    for (std::size_t i = 0; i < sequence->size(); ++i) sequence->frame(i);
  } catch (const meshflow::Error&) {
  }
  return 0;
}
