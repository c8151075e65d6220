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

/// The indices 0 .. key.size() - 1 ordered by key[i] (values below `buckets`), ties in index
/// order: a counting sort with per-block histograms joined in block order, parallel and
/// deterministic. Keys of `buckets` or more are left out (a sentinel for "no item").
/// O(n + buckets x blocks); indices must fit in Index.
template <typename Index>
std::vector<Index> stable_order_by_key(const std::vector<std::uint16_t>& key, std::size_t buckets);

/// radix_sort() followed by removal of duplicates.
void radix_sort_unique(std::vector<std::uint64_t>& keys);

}  // namespace meshflow
