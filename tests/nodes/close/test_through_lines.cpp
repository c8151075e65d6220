#include "nodes/close/through_lines.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "test_support.h"

namespace meshflow {
namespace {

struct ThroughLattice {
  Eigen::Vector3i size;
  std::vector<std::uint8_t> observed;  ///< 0 no data, 1 data outside, 2 data inside

  std::size_t index(int x, int y, int z) const {
    return (static_cast<std::size_t>(z) * static_cast<std::size_t>(size.y()) +
            static_cast<std::size_t>(y)) *
               static_cast<std::size_t>(size.x()) +
           static_cast<std::size_t>(x);
  }
  bool inside(const Eigen::Vector3i& q) const {
    return (q.array() >= 0).all() && (q.array() < size.array()).all();
  }
  bool seen(const Eigen::Vector3i& q) const { return observed[index(q.x(), q.y(), q.z())] != 0; }
};

// The oracle: each line walked node by node, each walled-in test by walking its rays.
std::vector<std::uint8_t> through_brute_force(const ThroughLattice& l) {
  std::vector<Eigen::Vector3i> dirs;
  for (int z = -1; z <= 1; ++z)
    for (int y = -1; y <= 1; ++y)
      for (int x = -1; x <= 1; ++x)
        if (x != 0 || y != 0 || z != 0) dirs.emplace_back(x, y, z);
  // The side of the first data along the ray, 0 when none: each step from q to q + d passes
  // the nodes q + s (s: d with some of its components zeroed, not all), the nearest (fewest
  // components) first, inside winning within a level; q + d last.
  const auto ray_meets = [&](Eigen::Vector3i q, const Eigen::Vector3i& d) {
    for (; l.inside(q + d); q += d)
      for (int level = 1; level <= 3; ++level) {
        int side = 0;
        for (int mask = 1; mask < 8; ++mask) {
          Eigen::Vector3i s = Eigen::Vector3i::Zero();
          int count = 0;
          for (int a = 0; a < 3; ++a)
            if ((mask >> a & 1) && d[a] != 0) {
              s[a] = d[a];
              ++count;
            }
          if (count != level || s.cwiseAbs().sum() != level) continue;
          const Eigen::Vector3i p = q + s;
          side = std::max(side, static_cast<int>(l.observed[l.index(p.x(), p.y(), p.z())]));
        }
        if (side != 0) return side;
      }
    return 0;
  };
  const auto walled = [&](const Eigen::Vector3i& q, const Eigen::Vector3i& line) {
    if (l.seen(q)) return false;
    for (const Eigen::Vector3i& e : dirs)
      if (e.dot(line) == 0 && ray_meets(q, e) != 1) return false;
    return true;
  };
  std::vector<std::uint8_t> out(l.observed.size(), 0);
  for (int z = 0; z < l.size.z(); ++z)
    for (int y = 0; y < l.size.y(); ++y)
      for (int x = 0; x < l.size.x(); ++x) {
        const Eigen::Vector3i q(x, y, z);
        if (l.seen(q)) continue;
        for (const Eigen::Vector3i& d : dirs) {
          if (ray_meets(q, d) || ray_meets(q, -d)) continue;
          // Three walled nodes in a row somewhere on the line (a tunnel, not a band's slit).
          const auto run = [&](const Eigen::Vector3i& s) {
            return l.inside(s + 2 * d) && walled(s, d) && walled(s + d, d) && walled(s + 2 * d, d);
          };
          bool any = run(q);
          for (Eigen::Vector3i s = q + d; l.inside(s) && !any; s += d) any = run(s);
          for (Eigen::Vector3i s = q - d; l.inside(s) && !any; s -= d) any = run(s);
          if (any) out[l.index(x, y, z)] = 1;
        }
      }
  return out;
}

TEST(ThroughLines, MatchesTheBruteForceWalkOnRandomLattices) {
  std::mt19937 rng(7);
  for (const double density : {0.02, 0.1, 0.25, 0.4}) {
    ThroughLattice l{{13, 11, 9}, {}};
    std::bernoulli_distribution seen(density), outside(0.7);
    l.observed.resize(static_cast<std::size_t>(l.size.prod()));
    for (auto& o : l.observed) o = seen(rng) ? (outside(rng) ? 1 : 2) : 0;
    // A square tube along z through z = 2..6 (its outside facing the axis), so that some lines
    // are walled in for more than one node in a row.
    for (int z = 2; z <= 6; ++z)
      for (int y = 1; y <= 9; ++y)
        for (int x = 2; x <= 10; ++x) {
          const int ring = std::max(std::abs(x - 6), std::abs(y - 5));
          if (ring >= 3) l.observed[l.index(x, y, z)] = ring == 3 ? 1 : 2;
        }
    const std::vector<std::uint8_t> fast = through_line_nodes(l.size, l.observed);
    const std::vector<std::uint8_t> slow = through_brute_force(l);
    ASSERT_EQ(fast.size(), slow.size());
    std::size_t marked = 0;
    for (std::size_t i = 0; i < fast.size(); ++i) {
      EXPECT_EQ(fast[i], slow[i]) << "node " << i << " at density " << density;
      marked += slow[i];
    }
    std::printf("[ through ] density %.2f: %zu of %zu nodes on through lines\n", density, marked,
                fast.size());
    if (density < 0.05) {
      EXPECT_GT(marked, 0u) << "the tube's lines";
    }
  }
}

// A slab (the band of its top face and of its hole's wall observed, the wall only in its
// upper third, as a scanner looking down into the hole sees it; the bottom unseen): the hole's
// axis is open all the way down, the unseen material under the top face is not.
ThroughLattice slab_with_hole() {
  ThroughLattice l{{41, 41, 41}, {}};
  l.observed.assign(static_cast<std::size_t>(l.size.prod()), 0);
  for (int z = 0; z < l.size.z(); ++z)
    for (int y = 0; y < l.size.y(); ++y)
      for (int x = 0; x < l.size.x(); ++x) {
        const float r = std::hypot(static_cast<float>(x - 20), static_cast<float>(y - 20));
        const bool top = z >= 28 && z <= 30 && r >= 8.0f && x >= 4 && x <= 36 && y >= 4 && y <= 36;
        const bool wall = z >= 21 && z <= 30 && r >= 8.0f && r < 10.0f;
        // Outside: the top face's upper layer, the wall's layer towards the axis.
        const bool out = (top && z == 30) || (wall && r < 9.0f);
        l.observed[l.index(x, y, z)] = top || wall ? (out ? 1 : 2) : 0;
      }
  return l;
}

TEST(ThroughLines, AnObservedHoleStaysOpenWhereItsWallsWereUnseen) {
  const ThroughLattice l = slab_with_hole();
  const std::vector<std::uint8_t> through = through_line_nodes(l.size, l.observed);
  for (int z = 0; z < l.size.z(); ++z) EXPECT_TRUE(through[l.index(20, 20, z)]) << "z " << z;
  // Under the top face, away from the hole, where the slab's bottom and the wall's lower part
  // were never seen: no line there is walled in.
  for (int z = 10; z <= 26; ++z)
    for (int x = 5; x <= 10; ++x) EXPECT_FALSE(through[l.index(x, 6, z)]) << x << ", 6, " << z;
}

TEST(ThroughLines, AnUnseenBottomOpensNothing) {
  // The band of a box's top and walls (its bottom unseen) and of a sphere above its unseen cap:
  // no node inside either is on a through line.
  ThroughLattice box{{30, 26, 22}, {}}, sphere{{33, 33, 33}, {}};
  box.observed.assign(static_cast<std::size_t>(box.size.prod()), 0);
  for (int z = 4; z < 19; ++z)
    for (int y = 4; y < 22; ++y)
      for (int x = 4; x < 26; ++x)
        box.observed[box.index(x, y, z)] =
            z >= 17 || x <= 5 || x >= 24 || y <= 5 || y >= 20
                ? (z == 18 || x == 4 || x == 25 || y == 4 || y == 21 ? 1 : 2)
                : 0;
  sphere.observed.assign(static_cast<std::size_t>(sphere.size.prod()), 0);
  for (int z = 0; z < 33; ++z)
    for (int y = 0; y < 33; ++y)
      for (int x = 0; x < 33; ++x) {
        const float r = Eigen::Vector3f(x - 16.0f, y - 16.0f, z - 16.0f).norm();
        sphere.observed[sphere.index(x, y, z)] =
            std::abs(r - 12.0f) < 1.5f && z > 7 ? (r >= 12.0f ? 1 : 2) : 0;
      }
  const std::vector<std::uint8_t> in_box = through_line_nodes(box.size, box.observed);
  for (int z = 4; z < 17; ++z)
    for (int y = 6; y < 20; ++y)
      for (int x = 6; x < 24; ++x) EXPECT_FALSE(in_box[box.index(x, y, z)]) << x << y << z;
  const std::vector<std::uint8_t> in_sphere = through_line_nodes(sphere.size, sphere.observed);
  for (int z = 0; z < 33; ++z)
    for (int y = 0; y < 33; ++y)
      for (int x = 0; x < 33; ++x) {
        if (Eigen::Vector3f(x - 16.0f, y - 16.0f, z - 16.0f).norm() < 12.0f) {
          EXPECT_FALSE(in_sphere[sphere.index(x, y, z)]) << x << ", " << y << ", " << z;
        }
      }
}

TEST(ThroughLines, ASphereSeenInPatchesOpensNothingInside) {
  // Three caps of a sphere seen (as three views 120 degrees apart see it), the rest unseen:
  // inside it, every ray meets the caps' inside first, so no node there is walled in.
  ThroughLattice s{{37, 37, 37}, {}};
  s.observed.assign(static_cast<std::size_t>(s.size.prod()), 0);
  const Eigen::Vector3f views[3] = {
      {1.0f, 0.0f, 0.3f}, {-0.5f, 0.87f, -0.3f}, {-0.5f, -0.87f, 0.3f}};
  std::size_t inside = 0;
  for (int z = 0; z < 37; ++z)
    for (int y = 0; y < 37; ++y)
      for (int x = 0; x < 37; ++x) {
        const Eigen::Vector3f q(x - 18.0f, y - 18.0f, z - 18.0f);
        const float r = q.norm();
        bool seen = false;
        for (const Eigen::Vector3f& v : views) seen = seen || q.dot(v.normalized()) > 0.4f * r;
        if (std::abs(r - 14.0f) < 1.5f && seen) s.observed[s.index(x, y, z)] = r >= 14.0f ? 1 : 2;
      }
  const std::vector<std::uint8_t> through = through_line_nodes(s.size, s.observed);
  for (int z = 0; z < 37; ++z)
    for (int y = 0; y < 37; ++y)
      for (int x = 0; x < 37; ++x) {
        if (Eigen::Vector3f(x - 18.0f, y - 18.0f, z - 18.0f).norm() >= 12.5f) continue;
        ++inside;
        EXPECT_FALSE(through[s.index(x, y, z)]) << x << ", " << y << ", " << z;
      }
  EXPECT_GT(inside, 5000u);
}

TEST(ThroughLines, ASlitBetweenThinPatchesOpensNothing) {
  // A sphere's band about one layer thick on each side (as a merged depth scan leaves it), seen
  // all over but for two pinholes one node wide where the face diagonal x = 0, y = z through
  // the centre crosses it (where patches nearly meet). That line meets no node with data, and
  // its outer pinhole node has the band's outside layer on every side across the line. A line
  // slipping diagonally between the band's nodes, or one walled node (a slit, not a tunnel),
  // must not open the sphere (run --merged of three views had a tunnel through its centre).
  ThroughLattice s{{41, 41, 41}, {}};
  s.observed.assign(static_cast<std::size_t>(s.size.prod()), 0);
  for (int z = 0; z < 41; ++z)
    for (int y = 0; y < 41; ++y)
      for (int x = 0; x < 41; ++x) {
        const Eigen::Vector3f q(x - 20.0f, y - 20.0f, z - 20.0f);
        const float r = q.norm();
        const bool slit = std::abs(q.y() - q.z()) < 0.5f && std::abs(q.x()) < 0.5f;
        if (std::abs(r - 15.0f) < 0.9f && !slit) s.observed[s.index(x, y, z)] = r >= 15.0f ? 1 : 2;
      }
  const std::vector<std::uint8_t> through = through_line_nodes(s.size, s.observed);
  std::size_t inside = 0;
  for (int z = 0; z < 41; ++z)
    for (int y = 0; y < 41; ++y)
      for (int x = 0; x < 41; ++x) {
        if (Eigen::Vector3f(x - 20.0f, y - 20.0f, z - 20.0f).norm() >= 13.5f) continue;
        ++inside;
        EXPECT_FALSE(through[s.index(x, y, z)]) << x << ", " << y << ", " << z;
      }
  EXPECT_GT(inside, 9000u);
}

TEST(ThroughLines, SameNodesWithOneAndTwoThreads) {
  const ThroughLattice l = slab_with_hole();
  const auto run = [&](int threads) {
    return test::with_threads(threads, [&] { return through_line_nodes(l.size, l.observed); });
  };
  EXPECT_EQ(run(1), run(2));
}

}  // namespace
}  // namespace meshflow
