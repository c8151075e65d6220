#include "nodes/cube/cube_table.h"

#include <cassert>

namespace meshflow {
namespace {

// Faces with their corners counter-clockwise seen from outside the cube.
constexpr std::array<std::array<int, 4>, 6> kFaces = {{{0, 4, 6, 2},    // x = 0
                                                       {1, 3, 7, 5},    // x = 1
                                                       {0, 1, 5, 4},    // y = 0
                                                       {2, 6, 7, 3},    // y = 1
                                                       {0, 2, 3, 1},    // z = 0
                                                       {4, 5, 7, 6}}};  // z = 1

int edge_between(int a, int b) {
  for (int e = 0; e < 12; ++e) {
    const auto& ce = kCubeEdges[static_cast<std::size_t>(e)];
    if ((ce[0] == a && ce[1] == b) || (ce[0] == b && ce[1] == a)) return e;
  }
  assert(false);
  return -1;
}

// True when cube edges a and b lie on a common face.
bool share_face(int a, int b) {
  for (const auto& face : kFaces) {
    int hits = 0;
    for (int i = 0; i < 4; ++i) {
      const int e = edge_between(face[static_cast<std::size_t>(i)],
                                 face[static_cast<std::size_t>((i + 1) % 4)]);
      hits += (e == a || e == b) ? 1 : 0;
    }
    if (hits == 2) return true;
  }
  return false;
}

// A fan apex whose diagonals all cross the cube's interior. A diagonal lying on a face (possible
// when a loop passes both segments of an ambiguous face) could be created by the neighbouring
// cell too, giving an edge with four faces.
std::size_t fan_apex(const std::vector<int>& loop) {
  const std::size_t n = loop.size();
  for (std::size_t a = 0; a < n; ++a) {
    bool ok = true;
    for (std::size_t k = 2; k + 1 < n && ok; ++k) ok = !share_face(loop[a], loop[(a + k) % n]);
    if (ok) return a;
  }
  return n;  // none (never happens for the 256 cases)
}

CubeCase build_case(int pattern) {
  auto inside = [pattern](int c) { return (pattern >> c) & 1; };
  // next[e] = the crossing edge that follows e on its loop.
  std::array<int, 12> next;
  next.fill(-1);
  for (const auto& face : kFaces) {
    // Walking the face counter-clockwise, each run of outside corners is entered by an
    // inside->outside edge and left by an outside->inside edge; one segment cuts it off.
    for (int i = 0; i < 4; ++i) {
      const int a = face[static_cast<std::size_t>(i)],
                b = face[static_cast<std::size_t>((i + 1) % 4)];
      if (!(inside(a) && !inside(b))) continue;
      for (int j = 1; j < 4; ++j) {
        const int c = face[static_cast<std::size_t>((i + j) % 4)];
        const int d = face[static_cast<std::size_t>((i + j + 1) % 4)];
        if (!inside(c) && inside(d)) {
          next[static_cast<std::size_t>(edge_between(a, b))] = edge_between(c, d);
          break;
        }
      }
    }
  }
  CubeCase out;
  std::array<bool, 12> used{};
  for (int start = 0; start < 12; ++start) {
    if (next[static_cast<std::size_t>(start)] < 0 || used[static_cast<std::size_t>(start)])
      continue;
    std::vector<int> loop;
    for (int e = start; !used[static_cast<std::size_t>(e)]; e = next[static_cast<std::size_t>(e)]) {
      used[static_cast<std::size_t>(e)] = true;
      loop.push_back(e);
    }
    // The loop runs clockwise seen from outside; reverse the fan to wind counter-clockwise.
    const std::size_t n = loop.size();
    const std::size_t apex = fan_apex(loop);
    assert(apex < n && "every loop of the 256 cases has a valid apex (checked by the tests)");
    const std::size_t a = apex < n ? apex : 0;
    out.loops.emplace_back(loop.begin(), loop.end());
    for (std::size_t k = 1; k + 1 < n; ++k) {
      out.triangles.push_back({static_cast<std::uint8_t>(loop[a]),
                               static_cast<std::uint8_t>(loop[(a + k + 1) % n]),
                               static_cast<std::uint8_t>(loop[(a + k) % n])});
    }
  }
  return out;
}

}  // namespace

const std::array<CubeCase, 256>& cube_cases() {
  static const std::array<CubeCase, 256> table = [] {
    std::array<CubeCase, 256> t;
    for (int p = 0; p < 256; ++p) t[static_cast<std::size_t>(p)] = build_case(p);
    return t;
  }();
  return table;
}

}  // namespace meshflow
