#pragma once
// Rgb8: an 8-bit RGB colour, the colour of points, vertices and image pixels.

#include <cstdint>

namespace meshflow {

struct Rgb8 {
  std::uint8_t r = 0, g = 0, b = 0;
  /// Same three channels.
  bool operator==(const Rgb8& o) const { return r == o.r && g == o.g && b == o.b; }
  /// Any channel differs.
  bool operator!=(const Rgb8& o) const { return !(*this == o); }
};
static_assert(sizeof(Rgb8) == 3, "Rgb8 is three packed bytes: image rows are arrays of it");

/// The colour halfway between a and b (each channel rounded half up), e.g. for a vertex that
/// splits an edge. O(1).
inline Rgb8 midpoint_color(const Rgb8& a, const Rgb8& b) {
  return Rgb8{static_cast<std::uint8_t>((a.r + b.r + 1) / 2),
              static_cast<std::uint8_t>((a.g + b.g + 1) / 2),
              static_cast<std::uint8_t>((a.b + b.b + 1) / 2)};
}

}  // namespace meshflow
