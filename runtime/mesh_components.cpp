#include "runtime/mesh_components.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "runtime/concurrent_disjoint_sets.h"

namespace meshflow {

std::vector<std::uint32_t> vertex_component_labels(const std::vector<Triangle>& triangles,
                                                   std::size_t vertex_count) {
  ConcurrentParents parent = concurrent_singletons(vertex_count);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, triangles.size(), 4096), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const Triangle& t = triangles[i];
      if (t[0] >= vertex_count) continue;
      for (int k = 1; k < 3; ++k)
        if (t[k] < vertex_count) concurrent_unite(parent, t[0], t[k]);
    }
  });
  std::vector<std::uint32_t> labels(vertex_count);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertex_count, 16384), [&](const auto& r) {
    for (std::size_t v = r.begin(); v != r.end(); ++v)
      labels[v] = concurrent_find(parent, static_cast<std::uint32_t>(v));
  });
  return labels;
}

}  // namespace meshflow
