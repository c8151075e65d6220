#include "runtime/radix_sort.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>

namespace meshflow {
namespace {

constexpr int kBits = 11;
constexpr std::size_t kBuckets = std::size_t{1} << kBits;
constexpr std::size_t kBlock = std::size_t{1} << 16;  // keys per parallel block

// One stable counting-sort pass on the digit at `shift`, src -> dst. Blocks are fixed-size and
// their offsets are laid out bucket by bucket, block by block, so the result does not depend
// on how blocks are scheduled.
void radix_pass(const std::vector<std::uint64_t>& src, std::vector<std::uint64_t>& dst, int shift) {
  const std::size_t n = src.size();
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<std::array<std::size_t, kBuckets>> offsets(blocks);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    auto& h = offsets[b];
    h.fill(0);
    const std::size_t end = std::min(n, (b + 1) * kBlock);
    for (std::size_t i = b * kBlock; i < end; ++i) ++h[(src[i] >> shift) & (kBuckets - 1)];
  });
  std::size_t sum = 0;
  for (std::size_t d = 0; d < kBuckets; ++d) {
    for (std::size_t b = 0; b < blocks; ++b) {
      const std::size_t c = offsets[b][d];
      offsets[b][d] = sum;
      sum += c;
    }
  }
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    auto& at = offsets[b];
    const std::size_t end = std::min(n, (b + 1) * kBlock);
    for (std::size_t i = b * kBlock; i < end; ++i)
      dst[at[(src[i] >> shift) & (kBuckets - 1)]++] = src[i];
  });
}

}  // namespace

void radix_sort(std::vector<std::uint64_t>& keys) {
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
    radix_pass(*src, *dst, shift);
    std::swap(src, dst);
  }
  if (src != &keys) keys.swap(buffer);
}

void radix_sort_unique(std::vector<std::uint64_t>& keys) {
  radix_sort(keys);
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
}

}  // namespace meshflow
