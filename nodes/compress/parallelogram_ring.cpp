#include "nodes/compress/parallelogram_ring.h"

#include "nodes/compress/closed_surface.h"

namespace meshflow::compress {
namespace {

constexpr std::uint32_t kRingNext[3] = {1, 2, 0};  // the corner after j in a triangle

}  // namespace

ParallelogramRing::ParallelogramRing(const std::vector<Triangle>& triangles,
                                     const std::vector<char>& hole, std::size_t vertices)
    : hole_(hole), first_(vertices + 1, 0) {
  for (const Triangle& t : triangles)
    for (std::uint32_t v : t) ++first_[v + 1];
  for (std::size_t v = 0; v < vertices; ++v) first_[v + 1] += first_[v];
  incident_.resize(first_[vertices]);
  std::vector<std::uint32_t> fill(first_.begin(), first_.end() - 1);
  for (std::uint32_t t = 0; t < triangles.size(); ++t)
    for (std::uint32_t j = 0; j < 3; ++j)
      incident_[fill[triangles[t][j]]++] = {triangles[t][kRingNext[j]],
                                            triangles[t][kRingNext[kRingNext[j]]]};
}

std::uint32_t ParallelogramRing::across(std::uint32_t from, std::uint32_t to) const {
  for (std::uint32_t i = first_[to]; i < first_[to + 1]; ++i)
    if (incident_[i].next == from) return incident_[i].prev;
  return kNone;
}

unsigned ParallelogramRing::gather(std::uint32_t k,
                                   const std::vector<std::array<std::int32_t, 3>>& grid,
                                   Parallelograms& out) const {
  unsigned count = 0;
  const auto known = [&](std::uint32_t v) { return v < k && !hole_[v]; };
  for (std::uint32_t i = first_[k]; i < first_[k + 1] && count < kMaxParallelograms; ++i) {
    const std::uint32_t x = incident_[i].next, y = incident_[i].prev;
    if (!known(x) || !known(y)) continue;
    const std::uint32_t w = across(x, y);
    if (w == kNone || !known(w)) continue;
    for (std::size_t a = 0; a < 3; ++a)
      out[count][a] = std::int64_t{grid[x][a]} + grid[y][a] - grid[w][a];
    ++count;
  }
  return count;
}

}  // namespace meshflow::compress
