#pragma once
// The uniform draw the closed test objects' samplers share (closed_objects.cpp,
// perforated_box.cpp).

#include <random>

namespace meshflow::synthetic {

/// A uniform draw from [0, 1) with 53 bits of `rng`'s next number. O(1).
inline double uniform01(std::mt19937_64& rng) {
  return static_cast<double>(rng() >> 11) * (1.0 / 9007199254740992.0);  // 53 bits
}

}  // namespace meshflow::synthetic
