#pragma once
// Radix sort for 64-bit keys (voxel keys, edge keys): linear time, deterministic, several times
// faster than a comparison sort for the millions of keys a sparse grid produces.

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <vector>

namespace meshflow {

/// Sorts `keys` ascending (LSD radix, 11-bit digits; digits that are equal in every key are
/// skipped, so keys spanning a small range cost few passes). Each pass is parallel over fixed
/// blocks of keys; the result is the same for any thread count. O(n) time, O(n) extra memory.
void radix_sort(std::vector<std::uint64_t>& keys);

/// A stable counting sort of the items 0 .. n - 1 by key_of(i) (values below `buckets`; items
/// whose key is `buckets` or more are left out): value_of(i) of the kept items ordered by key,
/// ties in index order, into `sorted` (resized; its capacity reused), and into `starts` (resized
/// to buckets + 1) where each key's items begin: key k's are sorted[starts[k] .. starts[k + 1]).
/// Per-block histograms joined in block order: parallel and deterministic. key_of and value_of
/// must be thread-safe. O(n + buckets x blocks).
template <typename Value, typename KeyOf, typename ValueOf>
void counting_sort(std::size_t n, std::size_t buckets, KeyOf key_of, ValueOf value_of,
                   std::vector<Value>& sorted, std::vector<std::size_t>& starts) {
  constexpr std::size_t kItemsPerBlock = std::size_t{1} << 16;
  const std::size_t blocks = (n + kItemsPerBlock - 1) / kItemsPerBlock;
  std::vector<std::size_t> offsets(blocks * buckets, 0);  // [block][bucket]
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    std::size_t* h = offsets.data() + b * buckets;
    const std::size_t end = std::min(n, (b + 1) * kItemsPerBlock);
    for (std::size_t i = b * kItemsPerBlock; i < end; ++i) {
      const std::size_t k = key_of(i);
      if (k < buckets) ++h[k];
    }
  });
  starts.resize(buckets + 1);
  std::size_t sum = 0;
  for (std::size_t d = 0; d < buckets; ++d) {
    starts[d] = sum;
    for (std::size_t b = 0; b < blocks; ++b) {
      const std::size_t c = offsets[b * buckets + d];
      offsets[b * buckets + d] = sum;
      sum += c;
    }
  }
  starts[buckets] = sum;
  sorted.resize(sum);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    std::size_t* at = offsets.data() + b * buckets;
    const std::size_t end = std::min(n, (b + 1) * kItemsPerBlock);
    for (std::size_t i = b * kItemsPerBlock; i < end; ++i) {
      const std::size_t k = key_of(i);
      if (k < buckets) sorted[at[k]++] = value_of(i);
    }
  });
}

/// counting_sort() as a new vector (the items' values ordered by key, ties in index order).
template <typename Value, typename KeyOf, typename ValueOf>
std::vector<Value> counting_sort(std::size_t n, std::size_t buckets, KeyOf key_of,
                                 ValueOf value_of) {
  std::vector<Value> sorted;
  std::vector<std::size_t> starts;
  counting_sort(n, buckets, key_of, value_of, sorted, starts);
  return sorted;
}

/// radix_sort() followed by removal of duplicates.
void radix_sort_unique(std::vector<std::uint64_t>& keys);

}  // namespace meshflow
