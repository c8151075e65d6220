#pragma once
// DisjointSets: union-find over the indices 0 .. n-1.

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

namespace meshflow {

/// Union-find with path halving. The root of every set is its lowest index, so labels do not
/// depend on the order of unite() calls. Not thread-safe; O(n) memory, near-constant time per call.
class DisjointSets {
 public:
  /// n singleton sets 0 .. n - 1.
  explicit DisjointSets(std::size_t n) { reset(n); }

  /// Starts over with n singletons, keeping the memory already held. O(n).
  void reset(std::size_t n) {
    parent_.resize(n);
    std::iota(parent_.begin(), parent_.end(), 0u);
  }

  /// The lowest index in x's set.
  std::uint32_t find(std::uint32_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }

  /// Joins the sets of a and b.
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }

  /// The root (lowest index) of every element's set.
  std::vector<std::uint32_t> labels() {
    for (std::uint32_t x = 0; x < parent_.size(); ++x) parent_[x] = find(x);
    return parent_;
  }

 private:
  std::vector<std::uint32_t> parent_;
};

}  // namespace meshflow
