#pragma once
// The numbers of the glTF 2.0 binary container (.glb) that meshflow's writer and reader share:
// chunk magics and the accessor component types (Khronos glTF 2.0 specification, 4.4 and 5.1.3).

#include <cstdint>

namespace meshflow::io::glb {

constexpr std::uint32_t kMagic = 0x46546C67;      // "glTF"
constexpr std::uint32_t kJsonChunk = 0x4E4F534A;  // "JSON"
constexpr std::uint32_t kBinChunk = 0x004E4942;   // "BIN\0"
constexpr int kUnsignedByte = 5121, kUnsignedShort = 5123, kUnsignedInt = 5125, kFloat = 5126;

}  // namespace meshflow::io::glb
