// The progressive coder's locked vertices (compress_progressive() with flags): in every level,
// at their quantised positions, and a locked border's edges in every level.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>
#include <utility>
#include <vector>

#include "nodes/compress/progressive_mesh.h"
#include "runtime/error.h"
#include "test_support.h"

namespace meshflow::compress {
namespace {

// grid_mesh(n) bent into a bumpy sheet, so the decimation has costs to rank.
TriangleMesh locked_test_sheet(std::uint32_t n) {
  TriangleMesh m = test::grid_mesh(n);
  for (Eigen::Vector3f& p : m.vertices)
    p.z() = 2.0f * std::sin(p.x() * 0.4f) * std::cos(p.y() * 0.3f);
  return m;
}

// The undirected border edges (edges of one triangle) of `m`, as `id` numbers its vertices.
std::set<std::pair<std::uint32_t, std::uint32_t>> numbered_border(
    const TriangleMesh& m, const std::vector<std::uint32_t>& id) {
  std::set<std::pair<std::uint32_t, std::uint32_t>> once, twice;
  for (const Triangle& t : m.triangles)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = id[t[k]], b = id[t[(k + 1) % 3]];
      const auto e = std::minmax(a, b);
      if (!once.insert(e).second) twice.insert(e);
    }
  for (const auto& e : twice) once.erase(e);
  return once;
}

// The sheet's border and every 7th vertex locked: the base mesh has every locked vertex (so every
// level has), each within half a quantiser step per axis of its input position, and every
// level's border is the input's border, edge for edge; the rest decimates to near the base
// ratio. No flags: the same bytes as without the argument; flags of another size: an error.
TEST(ProgressiveLocked, LockedVerticesAreInEveryLevelAndKeepTheBorder) {
  constexpr std::uint32_t n = 48;
  const TriangleMesh mesh = locked_test_sheet(n);
  std::vector<std::uint8_t> locked(mesh.vertices.size(), 0);
  for (std::uint32_t v = 0; v < mesh.vertices.size(); ++v) {
    const std::uint32_t i = v % n, j = v / n;
    locked[v] = i == 0 || j == 0 || i == n - 1 || j == n - 1 || v % 7 == 0 ? 1 : 0;
  }
  CompressConfig config;
  config.base_ratio = 1.0f / 16.0f;
  CompressReport report;
  const std::vector<unsigned char> bytes = compress_progressive(mesh, locked, config, &report);
  const std::vector<std::uint32_t>& order = report.vertex_order;  // decoded -> input vertex
  const std::vector<std::uint32_t> identity = [&] {
    std::vector<std::uint32_t> id(mesh.vertices.size());
    for (std::uint32_t v = 0; v < id.size(); ++v) id[v] = v;
    return id;
  }();
  const auto expected_border = numbered_border(mesh, identity);
  const std::size_t splits = report.splits;
  ASSERT_GT(splits, mesh.vertices.size() / 3) << "the unlocked vertices still collapse";
  for (std::size_t level : {std::size_t{0}, splits / 4, splits / 2, splits}) {
    ProgressiveLevel at;
    at.splits = level;
    const TriangleMesh decoded = decompress_progressive_level(bytes, "locked", at);
    std::vector<std::uint32_t> input_of(order.begin(), order.begin() + decoded.vertices.size());
    std::size_t locked_here = 0;
    for (std::size_t k = 0; k < decoded.vertices.size(); ++k) {
      if (!locked[input_of[k]]) continue;
      ++locked_here;
      const Eigen::Vector3f d = decoded.vertices[k] - mesh.vertices[input_of[k]];
      EXPECT_LE(d.cwiseAbs().maxCoeff(), report.quantizer.step / 2.0 + 1e-6) << k;
    }
    EXPECT_EQ(locked_here, static_cast<std::size_t>(std::count(locked.begin(), locked.end(), 1)))
        << "level " << level;
    EXPECT_EQ(numbered_border(decoded, input_of), expected_border) << "level " << level;
    if (level == 0) {
      EXPECT_LE(decoded.triangles.size(), mesh.triangles.size() / 3) << "the base is coarse";
    }
  }
  EXPECT_EQ(compress_progressive(mesh, {}, config), compress_progressive(mesh, config));
  locked.pop_back();
  EXPECT_THROW(compress_progressive(mesh, locked, config), Error);
}

}  // namespace
}  // namespace meshflow::compress
