#include "nodes/extract/feature_edge_flips.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
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

// An edge's place in the flip order: its end points' coordinates, lower end first (then the
// candidate's index, for coinciding end points only).
struct FlipEdgeKey {
  std::array<float, 6> ends;
  std::size_t pair;
  bool operator<(const FlipEdgeKey& o) const {
    return ends != o.ends ? ends < o.ends : pair < o.pair;
  }
};

FlipEdgeKey flip_edge_key(const Eigen::Vector3f& a, const Eigen::Vector3f& b, std::size_t pair) {
  const std::array<float, 3> x{a.x(), a.y(), a.z()}, y{b.x(), b.y(), b.z()};
  const bool a_first = x < y;
  const std::array<float, 3>& lo = a_first ? x : y;
  const std::array<float, 3>& hi = a_first ? y : x;
  return {{lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]}, pair};
}

}  // namespace

std::size_t flip_edges_between_features(TriangleMesh& mesh,
                                        const std::vector<std::uint8_t>& is_feature,
                                        const std::vector<std::uint8_t>* only_between) {
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
  // Edges met by exactly two fan triangles, taken in the order of their end points' positions
  // (not their indices): a mesh numbered otherwise (chunks stitched) makes the same flips.
  std::vector<std::size_t> pairs;
  for (std::size_t i = 0; i + 1 < opposite.size(); ++i) {
    if (opposite[i].first != opposite[i + 1].first) continue;
    if (i > 0 && opposite[i - 1].first == opposite[i].first) continue;
    if (i + 2 < opposite.size() && opposite[i + 2].first == opposite[i].first) continue;
    if (only_between != nullptr) {
      const auto a = static_cast<std::uint32_t>(opposite[i].first >> 32);
      const auto b = static_cast<std::uint32_t>(opposite[i].first & 0xffffffffu);
      if (!(*only_between)[a] || !(*only_between)[b]) continue;
    }
    pairs.push_back(i);
  }
  std::vector<FlipEdgeKey> keys(pairs.size());
  tbb::parallel_for(std::size_t{0}, pairs.size(), [&](std::size_t p) {
    const std::uint32_t t = opposite[pairs[p]].second;
    const Triangle x = feature_last(tris[t], lone_feature_corner(tris[t], is_feature));
    keys[p] = flip_edge_key(mesh.vertices[x[0]], mesh.vertices[x[1]], p);
  });
  tbb::parallel_sort(keys.begin(), keys.end());
  for (const FlipEdgeKey& key : keys) {
    const std::size_t i = pairs[key.pair];
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
