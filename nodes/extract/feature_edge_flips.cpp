#include "nodes/extract/feature_edge_flips.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <memory>
#include <unordered_set>

#include "runtime/parallel.h"

namespace meshflow {
namespace {

// Local index of the only feature vertex of t, or -1 when t has none or several.
int lone_feature_corner(const Triangle& t, const std::vector<std::uint8_t>& is_feature) {
  int found = -1;
  for (int j = 0; j < 3; ++j) {
    if (!is_feature[t[static_cast<std::size_t>(j)]]) continue;
    if (found >= 0) return -1;
    found = j;
  }
  return found;
}

// Triangle rotated so its lone feature vertex comes last: (a, b, f).
Triangle feature_last(const Triangle& t, int j) {
  return {t[static_cast<std::size_t>((j + 1) % 3)], t[static_cast<std::size_t>((j + 2) % 3)],
          t[static_cast<std::size_t>(j)]};
}

}  // namespace

std::size_t flip_edges_between_features(TriangleMesh& mesh,
                                        const std::vector<std::uint8_t>& is_feature) {
  auto& tris = mesh.triangles;
  const std::vector<std::uint32_t> fans = parallel_select_indices(
      tris.size(), [&](std::size_t t) { return lone_feature_corner(tris[t], is_feature) >= 0; });
  // Each fan triangle's edge opposite its feature vertex, sorted so the two sides of an edge
  // meet.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> opposite(fans.size());
  tbb::parallel_for(std::size_t{0}, fans.size(), [&](std::size_t i) {
    const Triangle t = feature_last(tris[fans[i]], lone_feature_corner(tris[fans[i]], is_feature));
    opposite[i] = {undirected_edge_key(t[0], t[1]), fans[i]};
  });
  tbb::parallel_sort(opposite.begin(), opposite.end());

  std::unique_ptr<std::atomic<std::uint32_t>[]> valence(
      new std::atomic<std::uint32_t>[mesh.vertices.size()]);
  tbb::parallel_for(std::size_t{0}, mesh.vertices.size(),
                    [&](std::size_t v) { valence[v].store(0, std::memory_order_relaxed); });
  tbb::parallel_for(std::size_t{0}, tris.size(), [&](std::size_t t) {
    for (std::uint32_t v : tris[t]) valence[v].fetch_add(1, std::memory_order_relaxed);
  });

  std::unordered_set<std::uint32_t> flipped;
  std::unordered_set<std::uint64_t> joined;  // feature-feature edges made so far
  std::size_t flips = 0;
  for (std::size_t i = 0; i + 1 < opposite.size(); ++i) {
    if (opposite[i].first != opposite[i + 1].first) continue;
    if (i + 2 < opposite.size() && opposite[i + 2].first == opposite[i].first) continue;
    const std::uint32_t t1 = opposite[i].second, t2 = opposite[i + 1].second;
    if (flipped.count(t1) || flipped.count(t2)) continue;
    const Triangle x = feature_last(tris[t1], lone_feature_corner(tris[t1], is_feature));
    const Triangle y = feature_last(tris[t2], lone_feature_corner(tris[t2], is_feature));
    const std::uint32_t a = x[0], b = x[1], f1 = x[2], f2 = y[2];
    if (y[0] != b || y[1] != a || f1 == f2) continue;  // not a consistently oriented pair
    if (valence[a].load(std::memory_order_relaxed) <= 3 ||
        valence[b].load(std::memory_order_relaxed) <= 3 ||
        joined.count(undirected_edge_key(f1, f2)))
      continue;
    const Triangle n1{a, f2, f1}, n2{f2, b, f1};
    const Eigen::Vector3f before = face_normal(mesh, x) + face_normal(mesh, y);
    const Eigen::Vector3f m1 = face_normal(mesh, n1), m2 = face_normal(mesh, n2);
    if (!(m1.dot(before) > 0.0f && m2.dot(before) > 0.0f)) continue;
    tris[t1] = n1;
    tris[t2] = n2;
    flipped.insert(t1);
    flipped.insert(t2);
    joined.insert(undirected_edge_key(f1, f2));
    valence[a].fetch_sub(1, std::memory_order_relaxed);
    valence[b].fetch_sub(1, std::memory_order_relaxed);
    valence[f1].fetch_add(1, std::memory_order_relaxed);
    valence[f2].fetch_add(1, std::memory_order_relaxed);
    ++flips;
  }
  return flips;
}

}  // namespace meshflow
