#include "runtime/mesh_components.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <utility>

namespace meshflow {
namespace {

using Parents = std::vector<std::atomic<std::uint32_t>>;

// The root of x's set. Every parent is an ancestor and no larger than its child, and an ancestor
// stays one, so pointing x at its grandparent (path halving) is right even while others link.
std::uint32_t find_root(Parents& parent, std::uint32_t x) {
  for (;;) {
    const std::uint32_t p = parent[x].load(std::memory_order_relaxed);
    if (p == x) return x;
    const std::uint32_t g = parent[p].load(std::memory_order_relaxed);
    if (g != p) parent[x].store(g, std::memory_order_relaxed);
    x = g;
  }
}

// Joins the sets of a and b: the larger root goes under the smaller, if it is still a root.
void unite(Parents& parent, std::uint32_t a, std::uint32_t b) {
  for (;;) {
    a = find_root(parent, a);
    b = find_root(parent, b);
    if (a == b) return;
    if (a < b) std::swap(a, b);
    std::uint32_t expected = a;
    if (parent[a].compare_exchange_strong(expected, b, std::memory_order_relaxed)) return;
  }
}

}  // namespace

std::vector<std::uint32_t> vertex_component_labels(const std::vector<Triangle>& triangles,
                                                   std::size_t vertex_count) {
  Parents parent(vertex_count);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertex_count, 16384), [&](const auto& r) {
    for (std::size_t v = r.begin(); v != r.end(); ++v)
      parent[v].store(static_cast<std::uint32_t>(v), std::memory_order_relaxed);
  });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, triangles.size(), 4096), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const Triangle& t = triangles[i];
      if (t[0] >= vertex_count) continue;
      for (int k = 1; k < 3; ++k)
        if (t[k] < vertex_count) unite(parent, t[0], t[k]);
    }
  });
  std::vector<std::uint32_t> labels(vertex_count);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertex_count, 16384), [&](const auto& r) {
    for (std::size_t v = r.begin(); v != r.end(); ++v)
      labels[v] = find_root(parent, static_cast<std::uint32_t>(v));
  });
  return labels;
}

}  // namespace meshflow
