#include "runtime/mesh_components.h"

#include <gtest/gtest.h>

#include <random>

#include "runtime/disjoint_sets.h"
#include "runtime/threads.h"

namespace meshflow {
namespace {

// The labels are the brute-force union-find's (the lowest index of each set) for any thread
// count: random triangles among groups of nearby vertices (many components, long chains
// across the groups), unused vertices and corners out of range among them.
TEST(MeshComponents, LabelsAreTheUnionFindsForAnyThreadCount) {
  std::mt19937 random(7);
  const std::uint32_t n = 60000;
  std::vector<Triangle> triangles;
  for (int i = 0; i < 40000; ++i) {
    const auto base = static_cast<std::uint32_t>(random() % (n - 40));
    const auto near = [&] { return base + static_cast<std::uint32_t>(random() % 40); };
    const std::uint32_t a = near(), b = near(), c = near();
    triangles.push_back({a, b, c});
  }
  triangles.push_back({n - 1, n + 5, 3});  // a corner beyond the vertices: left out
  DisjointSets sets(n);
  for (const Triangle& t : triangles)
    for (int k = 1; k < 3; ++k)
      if (t[0] < n && t[k] < n) sets.unite(t[0], t[k]);
  const std::vector<std::uint32_t> expected = sets.labels();
  std::size_t components = 0;
  for (std::uint32_t v = 0; v < n; ++v) components += expected[v] == v ? 1 : 0;
  ASSERT_GT(components, 100u);
  ASSERT_LT(components, n / 2);
  for (int threads : {1, 2, 4}) {
    ThreadLimit limit(threads);
    EXPECT_EQ(vertex_component_labels(triangles, n), expected) << threads << " threads";
  }
  EXPECT_TRUE(vertex_component_labels({}, 0).empty());
}

}  // namespace
}  // namespace meshflow
