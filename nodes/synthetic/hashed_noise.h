#pragma once
// Counter-based random numbers: the same key always gives the same value, so noise added in
// parallel loops does not depend on the thread count or the order of evaluation.

#include <cstdint>

namespace meshflow::synthetic {

/// Standard normal sample determined by `key` (SplitMix64 + Box-Muller).
float hashed_gaussian(std::uint64_t key);

}  // namespace meshflow::synthetic
