// Text clouds (XYZ / PTS / CSV): detected layouts, and an explicit column spec.
#include "fuzz_file.h"
#include "nodes/io/xyz_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  meshflow::fuzz::read_as(data, size, ".xyz",
                          [](const std::string& p) { meshflow::io::read_xyz(p); });
  meshflow::fuzz::read_as(data, size, ".xyz", [](const std::string& p) {
    meshflow::io::read_xyz(p, "x,y,z,nx,ny,nz,r,g,b");
  });
  return 0;
}
