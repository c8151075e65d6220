// The compressed mesh file (.mfc: Edgebreaker and progressive). Each input's checksums are
// recomputed first (inputs of 16 bytes and more: the file's, and for progressive images the
// prefix checksum and every packet's), so that mutations reach the fields and streams behind
// them; a wrong checksum is the tests' case (CompressedMeshFile.*). Every input is decoded in
// full, when progressive at a coarse level too, and through the prefix decoder (a network
// stream's first bytes): the whole image, the image without its file checksum (ending at a
// packet boundary) and its first half (cut inside a part).
#include <vector>

#include "nodes/compress/compressed_mesh.h"
#include "nodes/compress/progressive_mesh.h"
#include "runtime/error.h"

namespace {

void fuzz_mfc_prefix(const std::vector<unsigned char>& bytes, std::size_t size) {
  const std::vector<unsigned char> prefix(bytes.begin(),
                                          bytes.begin() + static_cast<std::ptrdiff_t>(size));
  try {
    meshflow::compress::decompress_progressive_prefix(prefix, "fuzz.mfc");
  } catch (const meshflow::Error&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<unsigned char> bytes(data, data + size);
  if (bytes.size() >= 16) meshflow::compress::reseal_progressive_mesh(bytes);
  try {
    meshflow::compress::decompress_mesh(bytes, "fuzz.mfc");
  } catch (const meshflow::Error&) {
  }
  try {
    meshflow::compress::ProgressiveLevel level;
    level.splits = 10;
    meshflow::compress::decompress_progressive_level(bytes, "fuzz.mfc", level);
  } catch (const meshflow::Error&) {
  }
  fuzz_mfc_prefix(bytes, bytes.size());
  if (bytes.size() >= 8) fuzz_mfc_prefix(bytes, bytes.size() - 8);
  fuzz_mfc_prefix(bytes, bytes.size() / 2);
  return 0;
}
