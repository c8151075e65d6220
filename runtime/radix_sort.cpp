#include "runtime/radix_sort.h"

#include <algorithm>
#include <array>

namespace meshflow {

void radix_sort(std::vector<std::uint64_t>& keys) {
  constexpr int kBits = 11;
  constexpr std::size_t kBuckets = std::size_t{1} << kBits;
  if (keys.size() < 2) return;
  std::uint64_t all_or = 0, all_and = ~std::uint64_t{0};
  for (std::uint64_t k : keys) {
    all_or |= k;
    all_and &= k;
  }
  const std::uint64_t varying = all_or ^ all_and;  // bits that differ between some keys
  std::vector<std::uint64_t> buffer(keys.size());
  std::vector<std::uint64_t>* src = &keys;
  std::vector<std::uint64_t>* dst = &buffer;
  for (int shift = 0; shift < 64; shift += kBits) {
    if (((varying >> shift) & (kBuckets - 1)) == 0) continue;
    std::array<std::size_t, kBuckets> offsets{};
    for (std::uint64_t k : *src) ++offsets[(k >> shift) & (kBuckets - 1)];
    std::size_t sum = 0;
    for (std::size_t& o : offsets) {
      const std::size_t c = o;
      o = sum;
      sum += c;
    }
    for (std::uint64_t k : *src) (*dst)[offsets[(k >> shift) & (kBuckets - 1)]++] = k;
    std::swap(src, dst);
  }
  if (src != &keys) keys.swap(buffer);
}

void radix_sort_unique(std::vector<std::uint64_t>& keys) {
  radix_sort(keys);
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
}

}  // namespace meshflow
