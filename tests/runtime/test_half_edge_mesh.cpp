#include "runtime/half_edge_mesh.h"

#include <gtest/gtest.h>

#include "runtime/error.h"
#include "test_support.h"

namespace meshflow {
namespace {

TriangleMesh grid(std::uint32_t n) { return test::grid_mesh(n); }

TEST(HalfEdgeMesh, ClosedTetrahedronHasMutualTwinsAndFullRings) {
  const HalfEdgeMesh h(test::tetrahedron());
  EXPECT_EQ(h.check(), "");
  EXPECT_EQ(h.face_count(), 4u);
  EXPECT_TRUE(h.border_loops().empty());
  for (std::uint32_t v = 0; v < 4; ++v) {
    EXPECT_FALSE(h.is_border_vertex(v));
    EXPECT_EQ(h.ring(v).size(), 3u);
    for (std::uint32_t e : h.ring(v)) EXPECT_EQ(h.from(e), v);
  }
  const TriangleMesh back = h.to_triangle_mesh();
  EXPECT_EQ(back.triangles, test::tetrahedron().triangles);
  EXPECT_EQ(back.vertices, test::tetrahedron().vertices);
}

TEST(HalfEdgeMesh, GridBorderIsOneLoopAndRingsMatchValences) {
  const HalfEdgeMesh h(grid(5));
  EXPECT_EQ(h.check(), "");
  const auto loops = h.border_loops();
  ASSERT_EQ(loops.size(), 1u);
  EXPECT_EQ(loops[0].size(), 16u);
  for (std::size_t i = 0; i < loops[0].size(); ++i)  // consecutive, closed
    EXPECT_EQ(h.to(loops[0][i]), h.from(loops[0][(i + 1) % loops[0].size()]));
  EXPECT_TRUE(h.is_border_vertex(0));
  EXPECT_FALSE(h.is_border_vertex(12));  // the centre
  EXPECT_EQ(h.ring(12).size(), 6u);
  EXPECT_EQ(h.ring(0).size(), 2u);  // corner (0, 0): two faces
}

TEST(HalfEdgeMesh, FlipReplacesTheDiagonalAndRefusesInvalidFlips) {
  TriangleMesh quad;
  quad.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  quad.triangles = {{0, 1, 2}, {0, 2, 3}};
  HalfEdgeMesh h(quad);
  // The only interior half-edges are the two halves of the diagonal 0-2.
  std::uint32_t diagonal = HalfEdgeMesh::kNone;
  for (std::uint32_t e = 0; e < h.half_edge_count(); ++e)
    if (!h.is_border(e)) diagonal = e;
  ASSERT_NE(diagonal, HalfEdgeMesh::kNone);
  EXPECT_TRUE(h.flip(diagonal));
  EXPECT_EQ(h.check(), "");
  const TriangleMesh flipped = h.to_triangle_mesh();
  // The new diagonal joins 1 and 3; both faces still face +z.
  for (const Triangle& t : flipped.triangles) {
    EXPECT_TRUE((t[0] == 1 || t[1] == 1 || t[2] == 1) && (t[0] == 3 || t[1] == 3 || t[2] == 3));
    EXPECT_GT(face_normal(flipped, t).z(), 0.0f);
  }
  EXPECT_EQ(h.border_loops().size(), 1u);
  // Border edges do not flip; in a tetrahedron every flip would duplicate an edge.
  for (std::uint32_t e = 0; e < h.half_edge_count(); ++e)
    if (h.is_border(e)) {
      EXPECT_FALSE(h.flip(e));
    }
  HalfEdgeMesh tet(test::tetrahedron());
  for (std::uint32_t e = 0; e < tet.half_edge_count(); ++e) EXPECT_FALSE(tet.flip(e));
  EXPECT_EQ(tet.check(), "");
}

TEST(HalfEdgeMesh, ManyFlipsOnAGridKeepEveryInvariant) {
  HalfEdgeMesh h(grid(12));
  std::size_t flips = 0;
  for (std::uint32_t e = 0; e < h.half_edge_count(); e += 7) flips += h.flip(e) ? 1 : 0;
  EXPECT_GT(flips, 20u);
  EXPECT_EQ(h.check(), "");
  const TriangleMesh m = h.to_triangle_mesh();
  const EdgeStatistics s = edge_statistics(m);
  EXPECT_EQ(s.non_manifold_edges, 0u);
  EXPECT_EQ(s.inconsistent_edges, 0u);
  EXPECT_EQ(s.boundary_edges, 44u);  // the outline is untouched
  for (const Triangle& t : m.triangles) EXPECT_GT(face_normal(m, t).z(), 0.0f);
}

std::size_t live_faces(const HalfEdgeMesh& h) {
  std::size_t n = 0;
  for (std::uint32_t f = 0; f < h.face_count(); ++f) n += h.face_alive(f) ? 1 : 0;
  return n;
}

// The half-edge a -> b, or kNone.
std::uint32_t half_edge(const HalfEdgeMesh& h, std::uint32_t a, std::uint32_t b) {
  for (std::uint32_t e : h.ring(a))
    if (h.to(e) == b) return e;
  return HalfEdgeMesh::kNone;
}

TEST(HalfEdgeMesh, CollapseRemovesAVertexAndTheFacesAlongItsEdge) {
  HalfEdgeMesh h(grid(5));
  // Interior edge 12 -> 13 (centre to its right neighbour): two faces go.
  const std::uint32_t e = half_edge(h, 12, 13);
  ASSERT_NE(e, HalfEdgeMesh::kNone);
  EXPECT_TRUE(h.collapse(e));
  EXPECT_EQ(h.check(), "");
  EXPECT_EQ(live_faces(h), 32u - 2u);
  EXPECT_EQ(h.outgoing(12), HalfEdgeMesh::kNone);
  const TriangleMesh m = h.to_triangle_mesh();
  EXPECT_EQ(m.vertices.size(), 24u);
  const EdgeStatistics s = edge_statistics(m);
  EXPECT_EQ(s.non_manifold_edges + s.inconsistent_edges, 0u);
  EXPECT_EQ(s.boundary_edges, 16u);
  // Border edge 1 -> 2 along the bottom: one face goes, the loop shortens by one.
  EXPECT_TRUE(h.collapse(half_edge(h, 1, 2)));
  EXPECT_EQ(h.check(), "");
  EXPECT_EQ(live_faces(h), 29u);
  ASSERT_EQ(h.border_loops().size(), 1u);
  EXPECT_EQ(h.border_loops()[0].size(), 15u);
}

TEST(HalfEdgeMesh, CollapseRefusesNonManifoldResults) {
  HalfEdgeMesh tet(test::tetrahedron());
  for (std::uint32_t e = 0; e < tet.half_edge_count(); ++e) EXPECT_FALSE(tet.collapse(e));
  // 3 x 3 grid: the diagonal 3 -> 7 joins two border vertices through the interior.
  HalfEdgeMesh h(grid(3));
  const std::uint32_t e = half_edge(h, 3, 7);
  ASSERT_NE(e, HalfEdgeMesh::kNone);
  EXPECT_FALSE(h.is_border(e));
  EXPECT_FALSE(h.collapse(e));
  EXPECT_EQ(h.check(), "");
  EXPECT_EQ(live_faces(h), 8u);
}

TEST(HalfEdgeMesh, SplitAddsAVertexOnTheEdge) {
  HalfEdgeMesh h(grid(4));
  const std::uint32_t m = h.split(half_edge(h, 5, 10), Eigen::Vector3f(1.5f, 1.5f, 0.0f));
  EXPECT_EQ(h.check(), "");
  EXPECT_EQ(m, 16u);
  EXPECT_EQ(live_faces(h), 20u);
  EXPECT_EQ(h.ring(m).size(), 4u);
  EXPECT_FALSE(h.is_border_vertex(m));
  const std::uint32_t b = h.split(half_edge(h, 0, 1), Eigen::Vector3f(0.5f, 0.0f, 0.0f));
  EXPECT_EQ(h.check(), "");
  EXPECT_TRUE(h.is_border_vertex(b));
  EXPECT_EQ(h.ring(b).size(), 2u);
  EXPECT_EQ(h.border_loops()[0].size(), 13u);
  const TriangleMesh out = h.to_triangle_mesh();
  for (const Triangle& t : out.triangles) EXPECT_GT(face_normal(out, t).z(), 0.0f);
  const EdgeStatistics s = edge_statistics(out);
  EXPECT_EQ(s.non_manifold_edges + s.inconsistent_edges, 0u);
}

TEST(HalfEdgeMesh, MixedEditsKeepEveryInvariant) {
  HalfEdgeMesh h(grid(10));
  std::uint32_t state = 7;
  auto random = [&] {
    state = state * 1664525u + 1013904223u;
    return state >> 8;
  };
  std::size_t done = 0;
  for (int step = 0; step < 3000; ++step) {
    const std::uint32_t e = random() % static_cast<std::uint32_t>(h.half_edge_count());
    if (!h.face_alive(HalfEdgeMesh::face(e))) continue;
    const std::uint32_t op = random() % 3;
    if (op == 0) {
      done += h.flip(e) ? 1 : 0;
    } else if (op == 1) {
      done += h.collapse(e) ? 1 : 0;
    } else {
      h.split(e, (h.position(h.from(e)) + h.position(h.to(e))) / 2);
      ++done;
    }
    ASSERT_EQ(h.check(), "") << "step " << step << " op " << op;
  }
  EXPECT_GT(done, 500u);
  const TriangleMesh m = h.to_triangle_mesh();
  const EdgeStatistics s = edge_statistics(m);
  EXPECT_EQ(s.non_manifold_edges + s.inconsistent_edges, 0u);
  for (const Triangle& t : m.triangles) EXPECT_GT(face_normal(m, t).z(), 0.0f);
  EXPECT_EQ(h.border_loops().size(), 1u);
}

TEST(HalfEdgeMesh, NonManifoldInputIsReportedNotStored) {
  TriangleMesh fin = test::tetrahedron();
  fin.vertices.emplace_back(1, 1, 1);
  fin.triangles.push_back({0, 1, 4});  // edge 0-1 now in three triangles
  try {
    HalfEdgeMesh h(fin);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("edge 0-1"), std::string::npos) << e.what();
  }
  TriangleMesh bow_tie;  // two triangles sharing only vertex 0
  bow_tie.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}};
  bow_tie.triangles = {{0, 1, 2}, {0, 3, 4}};
  try {
    HalfEdgeMesh h(bow_tie);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 0"), std::string::npos) << e.what();
  }
  TriangleMesh bad_index = test::tetrahedron();
  bad_index.triangles[2][1] = 9;
  EXPECT_THROW(HalfEdgeMesh{bad_index}, Error);
  TriangleMesh repeated = test::tetrahedron();
  repeated.triangles[0] = {1, 1, 2};
  EXPECT_THROW(HalfEdgeMesh{repeated}, Error);
}

}  // namespace
}  // namespace meshflow
