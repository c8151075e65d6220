#pragma once
// Deterministic parallel building blocks. Work is split into fixed-size blocks (independent of
// the number of threads) and per-block results are joined in block order, so outputs never
// depend on scheduling.

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace meshflow {

constexpr std::size_t kParallelBlock = 4096;

/// Replaces counts[i] by the sum of counts[0..i) and returns the total. Serial, O(n).
template <typename T>
T exclusive_scan_in_place(std::vector<T>& counts) {
  T sum = 0;
  for (T& c : counts) {
    const T v = c;
    c = sum;
    sum += v;
  }
  return sum;
}

/// The parts' elements in part order, into `out` (resized; its capacity reused), the copies in
/// parallel. T must be default-constructible. O(total elements).
template <typename T>
void concatenate_parts(const std::vector<std::vector<T>>& parts, std::vector<T>& out) {
  std::vector<std::size_t> offsets(parts.size());
  for (std::size_t i = 0; i < parts.size(); ++i) offsets[i] = parts[i].size();
  out.resize(exclusive_scan_in_place(offsets));
  tbb::parallel_for(std::size_t{0}, parts.size(), [&](std::size_t i) {
    std::copy(parts[i].begin(), parts[i].end(),
              out.begin() + static_cast<std::ptrdiff_t>(offsets[i]));
  });
}

/// The parts' elements in part order, as one new vector. O(total elements).
template <typename T>
std::vector<T> concatenate_parts(const std::vector<std::vector<T>>& parts) {
  std::vector<T> out;
  concatenate_parts(parts, out);
  return out;
}

/// Indices i in [0, n) with keep(i), in increasing order. `keep` must be thread-safe.
/// Two parallel passes (count, fill) over fixed blocks; O(n).
template <typename Predicate>
std::vector<std::uint32_t> parallel_select_indices(std::size_t n, Predicate keep) {
  const std::size_t blocks = (n + kParallelBlock - 1) / kParallelBlock;
  std::vector<std::uint32_t> offsets(blocks, 0);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    const std::size_t end = std::min(n, (b + 1) * kParallelBlock);
    std::uint32_t count = 0;
    for (std::size_t i = b * kParallelBlock; i < end; ++i) count += keep(i) ? 1u : 0u;
    offsets[b] = count;
  });
  std::vector<std::uint32_t> out(exclusive_scan_in_place(offsets));
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    const std::size_t end = std::min(n, (b + 1) * kParallelBlock);
    std::uint32_t at = offsets[b];
    for (std::size_t i = b * kParallelBlock; i < end; ++i) {
      if (keep(i)) out[at++] = static_cast<std::uint32_t>(i);
    }
  });
  return out;
}

}  // namespace meshflow
