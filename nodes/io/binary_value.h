#pragma once
// Scalar types of binary point formats (PLY, PCD) and how to decode them.

#include <cstdint>
#include <cstring>
#include <string_view>

namespace meshflow::io {

enum class ScalarType : std::uint8_t {
  kInt8,
  kUint8,
  kInt16,
  kUint16,
  kInt32,
  kUint32,
  kFloat32,
  kFloat64
};

/// Size in bytes of one value.
inline std::size_t scalar_size(ScalarType t) {
  constexpr std::size_t kSizes[] = {1, 1, 2, 2, 4, 4, 4, 8};
  return kSizes[static_cast<int>(t)];
}

/// Decodes one value at `p`; `swap` reverses the byte order (big-endian files on x86).
inline double decode_scalar(const unsigned char* p, ScalarType t, bool swap) {
  unsigned char b[8];
  const std::size_t n = scalar_size(t);
  for (std::size_t i = 0; i < n; ++i) b[i] = swap ? p[n - 1 - i] : p[i];
  switch (t) {
    case ScalarType::kInt8: {
      std::int8_t v;
      std::memcpy(&v, b, 1);
      return v;
    }
    case ScalarType::kUint8:
      return b[0];
    case ScalarType::kInt16: {
      std::int16_t v;
      std::memcpy(&v, b, 2);
      return v;
    }
    case ScalarType::kUint16: {
      std::uint16_t v;
      std::memcpy(&v, b, 2);
      return v;
    }
    case ScalarType::kInt32: {
      std::int32_t v;
      std::memcpy(&v, b, 4);
      return v;
    }
    case ScalarType::kUint32: {
      std::uint32_t v;
      std::memcpy(&v, b, 4);
      return v;
    }
    case ScalarType::kFloat32: {
      float v;
      std::memcpy(&v, b, 4);
      return v;
    }
    case ScalarType::kFloat64: {
      double v;
      std::memcpy(&v, b, 8);
      return v;
    }
  }
  return 0.0;
}

/// Raw 32 bits at `p` (for packed colours stored as float or uint32).
inline std::uint32_t decode_bits32(const unsigned char* p, bool swap) {
  unsigned char b[4];
  for (int i = 0; i < 4; ++i) b[i] = swap ? p[3 - i] : p[i];
  std::uint32_t v;
  std::memcpy(&v, b, 4);
  return v;
}

}  // namespace meshflow::io
