#pragma once
// Radix sort for 64-bit keys (voxel keys, edge keys): linear time, deterministic, several times
// faster than a comparison sort for the millions of keys a sparse grid produces.

#include <cstdint>
#include <vector>

namespace meshflow {

/// Sorts `keys` ascending (LSD radix, 11-bit digits; digits that are equal in every key are
/// skipped, so keys spanning a small range cost few passes). Each pass is parallel over fixed
/// blocks of keys; the result is the same for any thread count. O(n) time, O(n) extra memory.
void radix_sort(std::vector<std::uint64_t>& keys);

/// radix_sort() followed by removal of duplicates.
void radix_sort_unique(std::vector<std::uint64_t>& keys);

}  // namespace meshflow
