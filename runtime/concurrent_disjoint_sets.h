#pragma once
// A union-find that many threads unite at once: parents are atomics, roots are linked by
// compare-and-swap, always the larger index under the smaller, so each set's root is its lowest
// index whatever the order of the links (the labels DisjointSets gives serially).

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace meshflow {

/// Parent links of a concurrent union-find over 0 .. n - 1; parent[i] == i for a root.
using ConcurrentParents = std::vector<std::atomic<std::uint32_t>>;

/// n sets of one element each (parent[i] = i), written in parallel by the threads that will
/// unite them. n < 2^32. O(n).
inline ConcurrentParents concurrent_singletons(std::size_t n) {
  ConcurrentParents parent(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 16384),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        parent[i].store(static_cast<std::uint32_t>(i), std::memory_order_relaxed);
                    });
  return parent;
}

/// The root (lowest index) of x's set at the time of the call. Every parent is an ancestor and
/// no larger than its child, and an ancestor stays one, so pointing x at its grandparent (path
/// halving) is right even while other threads unite. Thread-safe with concurrent
/// concurrent_unite(); exact once every unite has returned. Near-constant time amortised.
inline std::uint32_t concurrent_find(ConcurrentParents& parent, std::uint32_t x) {
  for (;;) {
    const std::uint32_t p = parent[x].load(std::memory_order_relaxed);
    if (p == x) return x;
    const std::uint32_t g = parent[p].load(std::memory_order_relaxed);
    if (g != p) parent[x].store(g, std::memory_order_relaxed);
    x = g;
  }
}

/// Joins the sets of a and b: the larger root goes under the smaller, if it is still a root
/// (else the roots are found again). Thread-safe with concurrent calls; the sets once every call
/// has returned do not depend on their order. Near-constant time amortised.
inline void concurrent_unite(ConcurrentParents& parent, std::uint32_t a, std::uint32_t b) {
  for (;;) {
    a = concurrent_find(parent, a);
    b = concurrent_find(parent, b);
    if (a == b) return;
    if (a < b) std::swap(a, b);
    std::uint32_t expected = a;
    if (parent[a].compare_exchange_strong(expected, b, std::memory_order_relaxed)) return;
  }
}

}  // namespace meshflow
