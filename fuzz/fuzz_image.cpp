// Depth and colour images: PNG (libspng), TIFF (libtiff), PCLZF; the extension follows the
// input's magic bytes so the mutations reach each decoder.
#include <cstring>

#include "fuzz_file.h"
#include "nodes/io/image_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const char* ext = ".pclzf";
  if (size >= 4 && std::memcmp(data, "\x89PNG", 4) == 0) ext = ".png";
  if (size >= 2 && (std::memcmp(data, "II", 2) == 0 || std::memcmp(data, "MM", 2) == 0))
    ext = ".tiff";
  meshflow::fuzz::read_as(data, size, ext,
                          [](const std::string& p) { meshflow::io::read_depth_image_file(p); });
  meshflow::fuzz::read_as(data, size, ext,
                          [](const std::string& p) { meshflow::io::read_color_image_file(p); });
  return 0;
}
