// The compressed mesh file (.mfc: Edgebreaker and progressive). Each input's checksum is
// recomputed first (inputs of 16 bytes and more), so that mutations reach the fields behind
// it; a wrong checksum is the tests' case (CompressedMeshFile.*). Every input is decoded in
// full and, when progressive, at a coarse level too.
#include <vector>

#include "nodes/compress/compressed_mesh.h"
#include "nodes/compress/progressive_mesh.h"
#include "runtime/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<unsigned char> bytes(data, data + size);
  if (bytes.size() >= 16) meshflow::compress::reseal_compressed_mesh(bytes);
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
  return 0;
}
