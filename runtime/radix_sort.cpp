#include "runtime/radix_sort.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <utility>

#include "runtime/default_init.h"

namespace meshflow {
namespace {

constexpr int kBits = 11;
constexpr std::size_t kBuckets = std::size_t{1} << kBits;

// Keys per parallel block: an eighth of the keys, between 2^13 and 2^16 (so that a few ten
// thousand keys still make blocks for every thread, while the serial prefix over the blocks'
// histograms stays a small fraction of a pass). Any size sorts the same (a stable pass).
std::size_t block_size(std::size_t n) {
  return std::clamp<std::size_t>(n / 8, std::size_t{1} << 13, std::size_t{1} << 16);
}

// One stable counting-sort pass on the digit at `shift`, src -> dst. Blocks are fixed-size and
// their offsets are laid out bucket by bucket, block by block, so the result does not depend
// on how blocks are scheduled.
void radix_pass(const std::uint64_t* src, std::uint64_t* dst, std::size_t n, int shift) {
  const std::size_t block = block_size(n);
  const std::size_t blocks = (n + block - 1) / block;
  UninitVector<std::array<std::size_t, kBuckets>> offsets(blocks);  // zeroed by the threads
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    auto& h = offsets[b];
    h.fill(0);
    const std::size_t end = std::min(n, (b + 1) * block);
    for (std::size_t i = b * block; i < end; ++i) ++h[(src[i] >> shift) & (kBuckets - 1)];
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
    const std::size_t end = std::min(n, (b + 1) * block);
    for (std::size_t i = b * block; i < end; ++i)
      dst[at[(src[i] >> shift) & (kBuckets - 1)]++] = src[i];
  });
}

}  // namespace

void radix_sort(std::vector<std::uint64_t>& keys) {
  if (keys.size() < 2) return;
  using Bits = std::pair<std::uint64_t, std::uint64_t>;  // the keys' or, and
  const Bits bits = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, keys.size(), block_size(keys.size())),
      Bits{0, ~std::uint64_t{0}},
      [&](const tbb::blocked_range<std::size_t>& r, Bits b) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          b.first |= keys[i];
          b.second &= keys[i];
        }
        return b;
      },
      [](const Bits& a, const Bits& b) {
        return Bits{a.first | b.first, a.second & b.second};
      });
  const std::uint64_t varying = bits.first ^ bits.second;  // bits that differ between some keys
  const std::size_t n = keys.size();
  UninitVector<std::uint64_t> buffer(n);  // first written by the threads of the first pass
  std::uint64_t* src = keys.data();
  std::uint64_t* dst = buffer.data();
  for (int shift = 0; shift < 64; shift += kBits) {
    if (((varying >> shift) & (kBuckets - 1)) == 0) continue;
    radix_pass(src, dst, n, shift);
    std::swap(src, dst);
  }
  if (src != keys.data())  // an odd number of passes: the keys back, in parallel
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, block_size(n)),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        std::copy(src + r.begin(), src + r.end(),
                                  keys.begin() + static_cast<std::ptrdiff_t>(r.begin()));
                      });
}

void radix_sort_unique(std::vector<std::uint64_t>& keys) {
  radix_sort(keys);
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
}

}  // namespace meshflow
