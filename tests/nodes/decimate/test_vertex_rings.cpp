#include "nodes/decimate/vertex_rings.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "runtime/threads.h"

namespace meshflow {
namespace {

using Kind = VertexRings::Kind;

// A face rotated so that its smallest corner comes first (orientation kept): equal faces
// compare equal however they were written down.
Triangle canonical(Triangle t) {
  while (t[0] > t[1] || t[0] > t[2]) t = {t[1], t[2], t[0]};
  return t;
}

std::vector<Triangle> canonical_sorted(const std::vector<Triangle>& faces) {
  std::vector<Triangle> out;
  for (const Triangle& t : faces) out.push_back(canonical(t));
  std::sort(out.begin(), out.end());
  return out;
}

// An n x n vertex grid, two faces per cell (counter-clockwise), each face kept with
// probability `keep`: dropped faces leave holes, borders and vertices where fans meet.
std::vector<Triangle> grid_faces(int n, double keep, std::mt19937& rng) {
  std::bernoulli_distribution kept(keep);
  std::vector<Triangle> faces;
  const auto id = [n](int i, int j) { return static_cast<std::uint32_t>(j * n + i); };
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      if (kept(rng)) faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      if (kept(rng)) faces.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return faces;
}

// Neighbours of u in the face list.
std::set<std::uint32_t> neighbours(const std::vector<Triangle>& faces, std::uint32_t u) {
  std::set<std::uint32_t> out;
  for (const Triangle& t : faces)
    for (int i = 0; i < 3; ++i)
      if (t[i] == u) {
        out.insert(t[(i + 1) % 3]);
        out.insert(t[(i + 2) % 3]);
      }
  return out;
}

TEST(VertexRings, GridRingsAreFansInFaceOrientation) {
  std::mt19937 rng(1);
  const int n = 6;
  const std::vector<Triangle> faces = grid_faces(n, 1.0, rng);
  const VertexRings rings(faces, static_cast<std::size_t>(n * n));
  // An inner vertex of this grid has six neighbours, a corner one or two faces.
  const std::uint32_t inner = 2 * n + 2;
  EXPECT_EQ(rings.kind(inner), Kind::kClosed);
  EXPECT_EQ(rings.size(inner), 6u);
  EXPECT_EQ(rings.face_count(inner), 6u);
  EXPECT_EQ(rings.kind(0), Kind::kOpen);
  EXPECT_EQ(rings.face_count(0), 2u);
  EXPECT_EQ(rings.size(0), 3u);
  EXPECT_FALSE(rings.locked(inner));
  // Every consecutive pair of a ring is a face of the input, in its orientation.
  const std::vector<Triangle> expected = canonical_sorted(faces);
  for (std::uint32_t v = 0; v < static_cast<std::uint32_t>(n * n); ++v) {
    const std::uint32_t* r = rings.begin(v);
    const std::size_t size = rings.size(v);
    for (std::size_t k = 0; k < rings.face_count(v); ++k) {
      const Triangle face = canonical({v, r[k], r[(k + 1) % size]});
      EXPECT_TRUE(std::binary_search(expected.begin(), expected.end(), face)) << "vertex " << v;
    }
  }
  EXPECT_EQ(canonical_sorted(rings.triangles()), expected);
  const std::uint32_t* r = rings.begin(inner);
  EXPECT_TRUE(rings.share_face(inner, r[1], r[0]));
  EXPECT_TRUE(rings.share_face(inner, r[5], r[0]));  // around the closed ring
  EXPECT_FALSE(rings.share_face(inner, r[0], r[3]));
}

TEST(VertexRings, BowTiesNonManifoldEdgesAndRepeatedCorners) {
  // Two triangles meeting at vertex 0 only: a bow tie of two border fans.
  const std::vector<Triangle> bow_tie = {{0, 1, 2}, {0, 3, 4}};
  const VertexRings a(bow_tie, 5);
  EXPECT_EQ(a.kind(0), Kind::kFans);
  EXPECT_EQ(a.face_count(0), 2u);
  EXPECT_EQ(a.size(0), 5u);  // 1 2 | 3 4
  EXPECT_EQ(a.begin(0)[2], VertexRings::kSeparator);
  EXPECT_TRUE(a.locked(0));
  EXPECT_FALSE(a.locked(1));  // next to a bow tie only
  EXPECT_EQ(canonical_sorted(a.triangles()), canonical_sorted(bow_tie));
  EXPECT_TRUE(a.share_face(0, 1, 2));
  EXPECT_FALSE(a.share_face(0, 2, 3));  // consecutive entries, but across the separator

  // Six triangles meeting at vertex 0 (more fans than a ring's first room holds) and a hub of
  // forty faces.
  std::vector<Triangle> many;
  for (std::uint32_t k = 0; k < 6; ++k) many.push_back({0, 1 + 2 * k, 2 + 2 * k});
  for (std::uint32_t k = 0; k < 40; ++k) many.push_back({13, 14 + k, 14 + (k + 1) % 40});
  const VertexRings d(many, 54);
  EXPECT_EQ(d.kind(0), Kind::kFans);
  EXPECT_EQ(d.face_count(0), 6u);
  EXPECT_EQ(d.size(0), 17u);
  EXPECT_EQ(d.kind(13), Kind::kClosed);
  EXPECT_EQ(d.face_count(13), 40u);
  EXPECT_EQ(d.kind(14), Kind::kOpen);
  EXPECT_EQ(canonical_sorted(d.triangles()), canonical_sorted(many));

  // Three faces on the edge 0-1: both ends complex, their neighbours locked, every face kept.
  const std::vector<Triangle> fin = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}, {2, 1, 5}};
  const VertexRings b(fin, 6);
  EXPECT_EQ(b.kind(0), Kind::kComplex);
  EXPECT_EQ(b.kind(1), Kind::kComplex);
  EXPECT_EQ(b.face_count(0), 0u);
  EXPECT_TRUE(b.locked(2));
  EXPECT_TRUE(b.locked(5));
  EXPECT_EQ(canonical_sorted(b.triangles()), canonical_sorted(fin));

  // A face repeating a corner, and a face given twice.
  const std::vector<Triangle> repeated = {{0, 0, 1}, {1, 2, 3}, {1, 2, 3}, {3, 2, 4}};
  const VertexRings c(repeated, 5);
  EXPECT_EQ(c.kind(0), Kind::kComplex);
  EXPECT_EQ(c.kind(1), Kind::kComplex);
  EXPECT_EQ(c.kind(2), Kind::kComplex);
  EXPECT_EQ(c.kind(4), Kind::kOpen);
  EXPECT_EQ(canonical_sorted(c.triangles()), canonical_sorted(repeated));
}

// A fan of n faces around vertex 0 (rim 1 .. n, faces (0, i, i + 1) listed from face `first`
// on) is ordered alike on either side of the size where the ring build stops scanning a fan
// and indexes it (16 faces): closed from the first face listed, open from the rim vertex that
// starts it, two open fans in the order of their first vertices.
TEST(VertexRings, SmallAndLargeFansOrderAlike) {
  for (std::uint32_t n : {3u, 15u, 16u, 17u, 40u}) {
    const auto rim = [n](std::uint32_t i) { return 1 + i % n; };
    const auto fan = [&](std::uint32_t first, std::vector<std::uint32_t> dropped) {
      std::vector<Triangle> faces;
      for (std::uint32_t k = 0; k < n; ++k) {
        const std::uint32_t i = (first + k) % n;
        if (std::find(dropped.begin(), dropped.end(), i) == dropped.end())
          faces.push_back({0, rim(i), rim(i + 1)});
      }
      return VertexRings(faces, n + 1);
    };
    const std::string what = std::to_string(n) + " faces";
    const VertexRings closed = fan(2, {});
    ASSERT_EQ(closed.kind(0), Kind::kClosed) << what;
    std::vector<std::uint32_t> expected;
    for (std::uint32_t k = 0; k < n; ++k) expected.push_back(rim(2 + k));
    EXPECT_EQ(std::vector<std::uint32_t>(closed.begin(0), closed.end(0)), expected) << what;

    const VertexRings open = fan(2, {n - 1});  // face (0, n, 1) gone: the ring runs 1 .. n
    ASSERT_EQ(open.kind(0), Kind::kOpen) << what;
    expected.clear();
    for (std::uint32_t i = 0; i < n; ++i) expected.push_back(rim(i));
    EXPECT_EQ(std::vector<std::uint32_t>(open.begin(0), open.end(0)), expected) << what;

    if (n < 4) continue;
    const VertexRings two = fan(n / 2 + 1, {n - 1, n / 2});  // 1 .. n/2+1 | n/2+2 .. n
    ASSERT_EQ(two.kind(0), Kind::kFans) << what;
    expected.clear();
    for (std::uint32_t i = 0; i <= n / 2; ++i) expected.push_back(rim(i));
    expected.push_back(VertexRings::kSeparator);
    for (std::uint32_t i = n / 2 + 1; i < n; ++i) expected.push_back(rim(i));
    EXPECT_EQ(std::vector<std::uint32_t>(two.begin(0), two.end(0)), expected) << what;
  }
}

// triangles() against its definition, written out serially from the rings: every face of a
// non-complex corner from the ring of its smallest such corner (vertex order, then ring order),
// then the faces of only complex corners; the same on one and two threads. A grid of 12 100
// vertices with holes (its vertices span several of triangles()'s parallel blocks), after
// collapses along a row, which reorder rings.
TEST(VertexRings, TrianglesListFacesInVertexThenRingOrder) {
  std::mt19937 rng(11);
  const int n = 110;
  const std::vector<Triangle> faces = grid_faces(n, 0.9, rng);
  VertexRings rings(faces, static_cast<std::size_t>(n * n));
  std::size_t collapsed = 0;
  for (std::uint32_t u = 3 * n + 1; u + 1 < 4u * n; u += 3) {
    if (rings.locked(u) || rings.kind(u) != Kind::kClosed) continue;
    const std::uint32_t v = rings.begin(u)[0];
    const std::set<std::uint32_t> nu(rings.begin(u), rings.end(u));
    std::size_t common = 0;
    for (const std::uint32_t* x = rings.begin(v); x != rings.end(v); ++x) common += nu.count(*x);
    if (common == 2 && !rings.locked(v)) {  // the link condition holds
      rings.collapse(u, v);
      ++collapsed;
    }
  }
  ASSERT_GT(collapsed, 10u);
  const auto listed_later = [&](std::uint32_t corner, std::uint32_t owner) {
    return corner > owner || rings.kind(corner) == Kind::kComplex;
  };
  std::vector<Triangle> expected;
  for (std::uint32_t m = 0; m < static_cast<std::uint32_t>(n * n); ++m) {
    const std::uint32_t* r = rings.begin(m);
    const std::size_t size = rings.size(m);
    const std::size_t pairs = rings.kind(m) == Kind::kClosed ? size : (size == 0 ? 0 : size - 1);
    for (std::size_t i = 0; i < pairs; ++i) {
      const std::uint32_t b = r[i], c = r[(i + 1) % size];
      if (b == VertexRings::kSeparator || c == VertexRings::kSeparator) continue;
      if (listed_later(b, m) && listed_later(c, m)) expected.push_back({m, b, c});
    }
  }
  for (const Triangle& t : faces)
    if (rings.kind(t[0]) == Kind::kComplex && rings.kind(t[1]) == Kind::kComplex &&
        rings.kind(t[2]) == Kind::kComplex)
      expected.push_back(t);
  ASSERT_GT(expected.size(), 15000u);
  for (int threads : {1, 2}) {
    const ThreadLimit limit(threads);
    EXPECT_EQ(rings.triangles(), expected) << threads << " threads";
  }
}

// neighbours_among() against set intersection: every vertex's ring (v listed too, which never
// counts) and random lists of up to twenty distinct vertices (more than one block of eight), on
// grids with holes and bow ties, and around a hub of forty faces.
TEST(VertexRings, NeighboursAmongMatchesSetIntersection) {
  std::mt19937 rng(3);
  std::vector<Triangle> hub;
  for (std::uint32_t k = 0; k < 40; ++k) hub.push_back({0, 1 + k, 1 + (k + 1) % 40});
  for (int trial = 0; trial < 6; ++trial) {
    const int n = 6 + trial;
    const auto vertex_count = static_cast<std::uint32_t>(trial == 0 ? 41 : n * n);
    const std::vector<Triangle> faces = trial == 0 ? hub : grid_faces(n, 0.85, rng);
    const VertexRings rings(faces, vertex_count);
    for (std::uint32_t v = 0; v < vertex_count; ++v) {
      const std::set<std::uint32_t> around = neighbours(faces, v);
      std::vector<std::uint32_t> list(around.begin(), around.end());
      list.push_back(v);
      EXPECT_EQ(rings.neighbours_among(v, list.data(), list.size()), around.size())
          << "trial " << trial << ", vertex " << v;
      std::vector<std::uint32_t> all(vertex_count);
      for (std::uint32_t x = 0; x < vertex_count; ++x) all[x] = x;
      std::shuffle(all.begin(), all.end(), rng);
      all.resize(std::min<std::size_t>(all.size(), rng() % 21));
      const auto expected = static_cast<std::size_t>(
          std::count_if(all.begin(), all.end(), [&](std::uint32_t x) { return around.count(x); }));
      EXPECT_EQ(rings.neighbours_among(v, all.data(), all.size()), expected)
          << "trial " << trial << ", vertex " << v << ", " << all.size() << " listed";
    }
  }
}

// Random collapses that meet collapse()'s preconditions, checked against the same collapses
// applied to a plain face list (faces with both ends vanish, the others get v for u), on grids
// with holes and bow ties, after every collapse; the rings must also be what a fresh build
// from the face list gives (the same kinds and face counts). Every other collapse is prepared by
// reserve_collapse() (as parallel collapses are). Rings grow past the 14 entries a vertex's record
// holds (collapses onto one vertex), so collapses move rings out of their records and on within
// the shared storage.
TEST(VertexRings, CollapsesMatchAFaceListOracle) {
  std::mt19937 rng(5);
  std::size_t largest_ring = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const int n = 5 + trial % 6;
    const std::size_t vertex_count = static_cast<std::size_t>(n * n);
    std::vector<Triangle> faces = grid_faces(n, trial % 2 == 0 ? 1.0 : 0.8, rng);
    const ThreadLimit threads(1 + trial % 2);  // rings built on one or two threads
    VertexRings rings(faces, vertex_count);
    std::size_t collapses = 0;
    // In every other trial, every other attempt moves a neighbour of the middle vertex onto it:
    // its ring grows.
    const auto hub = static_cast<std::uint32_t>((n / 2) * n + n / 2);
    for (int attempt = 0; attempt < 400 && faces.size() > 4; ++attempt) {
      const bool grow = trial % 2 == 0 && attempt % 2 == 0 && rings.face_count(hub) != 0;
      const std::uint32_t u = grow ? rings.begin(hub)[rng() % rings.size(hub)]
                                   : static_cast<std::uint32_t>(rng() % vertex_count);
      if (u == VertexRings::kSeparator || rings.locked(u) || rings.face_count(u) == 0) continue;
      const std::uint32_t* r = rings.begin(u);
      const std::size_t size = rings.size(u);
      const bool open = rings.kind(u) == Kind::kOpen;
      const std::uint32_t v = grow   ? hub
                              : open ? (rng() % 2 == 0 ? r[0] : r[size - 1])
                                     : r[rng() % size];
      if (open && v != r[0] && v != r[size - 1]) continue;
      // Link condition: the common neighbours are the opposite corners of the faces of u-v.
      std::set<std::uint32_t> opposite, common;
      std::size_t shared = 0;
      for (const Triangle& t : faces)
        if (std::count(t.begin(), t.end(), u) != 0 && std::count(t.begin(), t.end(), v) != 0) {
          ++shared;
          for (std::uint32_t x : t)
            if (x != u && x != v) opposite.insert(x);
        }
      const std::set<std::uint32_t> nu = neighbours(faces, u), nv = neighbours(faces, v);
      std::set_intersection(nu.begin(), nu.end(), nv.begin(), nv.end(),
                            std::inserter(common, common.begin()));
      if (common != opposite || shared != (open ? 1u : 2u)) continue;
      std::vector<Triangle> next;
      for (Triangle t : faces) {
        if (std::count(t.begin(), t.end(), v) != 0 && std::count(t.begin(), t.end(), u) != 0)
          continue;
        for (std::uint32_t& x : t)
          if (x == u) x = v;
        next.push_back(t);
      }
      // Skip collapses that would leave two faces on the same three corners (a tetrahedron's
      // fold-over, refused by the decimator's normal test): the face list could not hold it.
      const std::vector<Triangle> sorted = canonical_sorted(next);
      bool folded = false;
      for (std::size_t i = 0; i < sorted.size(); ++i) {
        Triangle key = sorted[i];
        std::sort(key.begin(), key.end());
        for (std::size_t j = i + 1; j < sorted.size(); ++j) {
          Triangle other = sorted[j];
          std::sort(other.begin(), other.end());
          folded = folded || other == key;
        }
      }
      if (folded) continue;
      const std::string what = "trial " + std::to_string(trial) + ", " + std::to_string(u) +
                               " -> " + std::to_string(v) + " (collapse " +
                               std::to_string(collapses) + ")";
      if (collapses % 2 == 1) rings.reserve_collapse(u, v);
      ASSERT_EQ(rings.collapse(u, v), shared) << what;
      largest_ring = std::max(largest_ring, rings.size(v));
      faces = next;
      ++collapses;
      ASSERT_EQ(canonical_sorted(rings.triangles()), sorted) << what;
      ASSERT_EQ(rings.size(u), 0u) << what;
      const VertexRings fresh(faces, vertex_count);
      for (std::uint32_t x = 0; x < vertex_count; ++x) {
        if (x == u) continue;
        ASSERT_EQ(rings.kind(x) == Kind::kComplex, fresh.kind(x) == Kind::kComplex)
            << what << ", vertex " << x;
        ASSERT_EQ(rings.face_count(x), fresh.face_count(x)) << what << ", vertex " << x;
      }
    }
    EXPECT_GT(collapses, 5u) << "trial " << trial;
  }
  EXPECT_GT(largest_ring, 20u);
}

}  // namespace
}  // namespace meshflow
