// Mesh files: OBJ, OFF, binary or ascii STL and GLB (read_mesh dispatches by extension).
#include "fuzz_file.h"
#include "nodes/io/mesh_readers.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  for (const char* ext : {".obj", ".off", ".stl", ".glb"})
    meshflow::fuzz::read_as(data, size, ext,
                            [](const std::string& p) { meshflow::io::read_mesh(p); });
  return 0;
}
