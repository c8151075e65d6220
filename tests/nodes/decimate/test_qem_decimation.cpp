#include "nodes/decimate/qem_decimation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <string>

#include "nodes/eval/completeness.h"
#include "nodes/eval/surface_eval.h"
#include "nodes/synthetic/depth_sequence.h"
#include "nodes/triangulate/depth_triangulation.h"
#include "runtime/error.h"
#include "runtime/threads.h"

namespace meshflow {
namespace {

// An n x n grid over [0, 1]^2 with heights z(x, y), two triangles per cell (upward normals).
template <typename Height>
TriangleMesh height_field(int n, Height z) {
  TriangleMesh m;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const float x = static_cast<float>(i) / static_cast<float>(n - 1);
      const float y = static_cast<float>(j) / static_cast<float>(n - 1);
      m.vertices.emplace_back(x, y, z(x, y));
    }
  auto id = [n](int i, int j) { return static_cast<std::uint32_t>(j * n + i); };
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

float wave(float x, float y) { return 0.05f * std::sin(6.0f * x) * std::cos(4.0f * y); }

Eigen::Vector3f wave_normal(float x, float y) {
  const float dx = 0.3f * std::cos(6.0f * x) * std::cos(4.0f * y);
  const float dy = -0.2f * std::sin(6.0f * x) * std::sin(4.0f * y);
  return Eigen::Vector3f(-dx, -dy, 1.0f).normalized();
}

QemConfig plain_config() {
  QemConfig c;
  c.divide_by_depth2 = false;
  return c;
}

// A height field decimated to a quarter: at most a quarter of its triangles left, manifold,
// consistently oriented, no degenerate face, one border loop.
void expect_quarter_with_one_border(const TriangleMesh& in, const TriangleMesh& out,
                                    const std::string& what) {
  EXPECT_LE(out.triangles.size(), in.triangles.size() / 4 + 1) << what;
  const MeshTopology topology = mesh_topology(out);
  EXPECT_EQ(topology.edges.non_manifold_edges, 0u) << what;
  EXPECT_EQ(topology.edges.inconsistent_edges, 0u) << what;
  EXPECT_EQ(topology.degenerate_faces, 0u) << what;
  EXPECT_EQ(topology.boundary_loops, 1u) << what;
}

// The wave decimated to a quarter, by the walk or independent collapses: measured vertices,
// manifold, the border's shape and corners, no face turned over, close to the input.
void keeps_measured_vertices_topology_border_and_normals(bool independent) {
  const TriangleMesh in = height_field(80, wave);
  QemReport report;
  QemConfig config = plain_config();
  config.independent_collapses = independent;
  const TriangleMesh out = qem_decimate(in, config, &report);
  std::printf(
      "[ qem ] %zu -> %zu triangles; %zu collapses, rejected: %zu topology, %zu normal, "
      "%zu border; Hausdorff %.5f\n",
      in.triangles.size(), out.triangles.size(), report.collapses, report.rejected_topology,
      report.rejected_normal, report.rejected_border, hausdorff_distance(out, in));
  expect_quarter_with_one_border(in, out, "wave");
  // Vertices stay where they were measured.
  std::map<std::array<float, 3>, bool> measured;
  for (const auto& v : in.vertices) measured[{v.x(), v.y(), v.z()}] = true;
  for (const auto& v : out.vertices) EXPECT_TRUE(measured.count({v.x(), v.y(), v.z()}));
  // The border keeps its shape: border vertices stay on the unit square's outline, and the
  // four corners are kept (the border turns there).
  for (const BorderEdge& e : border_edges(out))
    for (std::uint32_t v : {e.a, e.b}) {
      const Eigen::Vector3f& p = out.vertices[v];
      EXPECT_TRUE(p.x() == 0.0f || p.x() == 1.0f || p.y() == 0.0f || p.y() == 1.0f);
    }
  for (const auto& corner :
       {Eigen::Vector2f(0, 0), Eigen::Vector2f(1, 0), Eigen::Vector2f(0, 1), Eigen::Vector2f(1, 1)})
    EXPECT_TRUE(std::any_of(out.vertices.begin(), out.vertices.end(), [&](const auto& v) {
      return v.x() == corner.x() && v.y() == corner.y();
    }));
  // No face turned over: every normal within 60 degrees of the surface's at its centroid.
  for (const Triangle& t : out.triangles) {
    const Eigen::Vector3f c = (out.vertices[t[0]] + out.vertices[t[1]] + out.vertices[t[2]]) / 3;
    EXPECT_GT(face_normal(out, t).dot(wave_normal(c.x(), c.y())), 0.5f);
  }
  EXPECT_LT(hausdorff_distance(out, in), 0.01);
}

TEST(QemDecimation, KeepsMeasuredVerticesTopologyBorderAndNormals) {
  for (bool independent : {false, true}) {
    SCOPED_TRACE(independent ? "independent collapses" : "walk");
    keeps_measured_vertices_topology_border_and_normals(independent);
  }
}

TEST(QemDecimation, NeedleAndSharpEdgePenaltiesLeaveFewerThinTriangles) {
  const TriangleMesh in = height_field(60, [](float x, float y) {
    return 0.3f * std::abs(x - 0.5f) + 0.01f * std::sin(17.0f * y);  // a valley with ripples
  });
  auto thin = [](const TriangleMesh& m) {
    std::size_t n = 0;
    for (const Triangle& t : m.triangles)
      for (int i = 0; i < 3; ++i) {
        const Eigen::Vector3f e1 = m.vertices[t[(i + 1) % 3]] - m.vertices[t[i]];
        const Eigen::Vector3f e2 = m.vertices[t[(i + 2) % 3]] - m.vertices[t[i]];
        if (std::atan2(e1.cross(e2).norm(), e1.dot(e2)) < 13.0f * 3.14159265f / 180.0f) {
          ++n;
          break;
        }
      }
    return n;
  };
  QemConfig no_penalty = plain_config();
  no_penalty.penalty = 1.0f;
  const std::size_t with = thin(qem_decimate(in, plain_config()));
  const std::size_t without = thin(qem_decimate(in, no_penalty));
  std::printf(
      "[ qem ] triangles with an angle under 13 degrees: %zu with the penalty, %zu "
      "without\n",
      with, without);
  EXPECT_LT(with, without);
}

TEST(QemDecimation, DividingByDepthSquaredThinsTheFarPartMore) {
  // A noisy plane from 1 m to 5 m ahead of the viewpoint (noise grows with depth^2).
  const TriangleMesh in = height_field(70, [](float x, float y) {
    const float depth = 1.0f + 4.0f * y;
    const float hash = std::sin(12.9898f * x * 70.0f + 78.233f * y * 70.0f) * 43758.5453f;
    return 0.002f * depth * depth * (hash - std::floor(hash) - 0.5f);
  });
  QemConfig depth = plain_config();
  depth.divide_by_depth2 = true;
  depth.viewpoint = Eigen::Vector3f(0.5f, -1.0f, 0.0f);  // y = 0 is 1 m away
  auto far_share = [](const TriangleMesh& m) {
    std::size_t far = 0;
    for (const auto& v : m.vertices) far += v.y() > 0.5f ? 1 : 0;
    return static_cast<double>(far) / static_cast<double>(m.vertices.size());
  };
  const double with = far_share(qem_decimate(in, depth));
  const double without = far_share(qem_decimate(in, plain_config()));
  std::printf("[ qem ] share of vertices in the far half: %.3f dividing by depth^2, %.3f not\n",
              with, without);
  EXPECT_LT(with, without);
}

TEST(QemDecimation, RoomFrameQualityForNaiveAndQuadtreeMeshes) {
  const PinholeIntrinsics k{320, 240, 262.5f, 262.5f, 159.5f, 119.5f};
  const DepthFrame frame =
      synthetic::render_depth(synthetic::demo_room_scene(), k,
                              synthetic::look_at({-2.5f, -1.5f, 1.4f}, {0.5f, 1.0f, 0.5f}), 0.001f);
  const PointGrid grid = grid_from_depth(frame, DepthFilterConfig{});
  DepthTriangulationConfig rqt_config;
  rqt_config.method = DepthTriangulationMethod::kRestrictedQuadtree;
  const TriangleMesh naive = mesh_from_pixel_triangles(grid, triangulate_grid(grid, {}));
  const TriangleMesh rqt = mesh_from_pixel_triangles(grid, triangulate_grid(grid, rqt_config));
  QemConfig qem;
  qem.viewpoint = grid.eye;
  const TriangleMesh naive_qem = qem_decimate(naive, qem);
  const TriangleMesh rqt_qem = qem_decimate(rqt, qem);
  std::printf("[ qem ] naive     %7zu triangles\n", naive.triangles.size());
  for (const auto& [name, m] :
       {std::pair<const char*, const TriangleMesh*>{"naive+qem", &naive_qem},
        {"rqt", &rqt},
        {"rqt+qem", &rqt_qem}}) {
    const Completeness c = completeness(*m, naive, k, frame.T_world_camera);
    std::printf(
        "[ qem ] %-9s %7zu triangles (%.1f%% of naive), Hausdorff %.4f m, h_n %.4f, "
        "h_c %.4f\n",
        name, m->triangles.size(),
        100.0 * static_cast<double>(m->triangles.size()) /
            static_cast<double>(naive.triangles.size()),
        hausdorff_distance(*m, naive), c.kept(), c.genuine());
    const MeshTopology topology = mesh_topology(*m);
    EXPECT_EQ(topology.edges.non_manifold_edges, 0u) << name;
    EXPECT_EQ(topology.edges.inconsistent_edges, 0u) << name;
    EXPECT_GE(c.kept(), 0.98) << name;
  }
  EXPECT_LE(naive_qem.triangles.size(), naive.triangles.size() / 4 + 1);
}

TEST(QemDecimation, SameResultWithOneAndTwoThreads) {
  // A noisy frame of the room through the quadtree: borders, occlusion edges, every check.
  const PinholeIntrinsics k{320, 240, 262.5f, 262.5f, 159.5f, 119.5f};
  const DepthFrame frame =
      synthetic::render_depth(synthetic::demo_room_scene(), k,
                              synthetic::look_at({-2.5f, -1.5f, 1.4f}, {0.5f, 1.0f, 0.5f}), 0.004f);
  DepthTriangulationConfig config;
  config.method = DepthTriangulationMethod::kRestrictedQuadtree;
  config.decimate_to = 0.25f;
  std::vector<TriangleMesh> meshes;
  for (int threads : {1, 2}) {
    ThreadLimit limit(threads);
    meshes.push_back(triangulate_depth(frame, config));
  }
  ASSERT_GT(meshes[0].triangles.size(), 1000u);
  EXPECT_EQ(meshes[0].triangles, meshes[1].triangles);
  EXPECT_EQ(meshes[0].vertices, meshes[1].vertices);
}

// On a plane every collapse costs nothing, so every collapse a pass re-evaluates stays within
// its limit: in the walk (one collapse at a time), vertices that took a collapse (reading the
// faces they took over) and their neighbours collapse again in the same pass, and one pass
// reaches the target (re-evaluating serially or in parallel chunks).
TEST(QemDecimation, GrownVerticesCollapseAgainInTheSamePass) {
  const TriangleMesh in = height_field(60, [](float, float) { return 0.0f; });
  for (std::size_t walk_chunk : {std::size_t{0}, std::size_t{64}}) {
    QemConfig config = plain_config();
    config.independent_collapses = false;
    config.walk_chunk = walk_chunk;
    QemReport report;
    const TriangleMesh out = qem_decimate(in, config, &report);
    const std::string what = "chunk " + std::to_string(walk_chunk);
    EXPECT_EQ(report.passes, 1u) << what;
    expect_quarter_with_one_border(in, out, what);
    for (const Triangle& t : out.triangles) {  // every face still faces up
      const Eigen::Vector3f n =
          (out.vertices[t[1]] - out.vertices[t[0]]).cross(out.vertices[t[2]] - out.vertices[t[0]]);
      EXPECT_GT(n.z(), 0.0f) << what;
    }
  }
}

// Random height fields with a round hole, noise and random quad diagonals, decimated to
// several ratios: collapses taken late in a pass, next to earlier ones, must keep the mesh as
// manifold as the per-pass evaluations would, and the result independent of the thread count.
TEST(QemDecimation, RandomNoisyMeshesWithHolesStayManifold) {
  std::mt19937 rng(7);
  std::normal_distribution<float> gauss(0.0f, 1.0f);
  for (int trial = 0; trial < 24; ++trial) {
    const int n = 8 + static_cast<int>(rng() % 33);
    const float noise = static_cast<float>(rng() % 4) * 0.01f;
    const float hole = static_cast<float>(rng() % 3) * 0.15f;
    TriangleMesh in;
    std::vector<std::int64_t> id(static_cast<std::size_t>(n * n), -1);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const float x = static_cast<float>(i) / static_cast<float>(n - 1);
        const float y = static_cast<float>(j) / static_cast<float>(n - 1);
        if ((x - 0.5f) * (x - 0.5f) + (y - 0.4f) * (y - 0.4f) < hole * hole) continue;
        id[static_cast<std::size_t>(j * n + i)] = static_cast<std::int64_t>(in.vertices.size());
        in.vertices.emplace_back(x, y, 2.0f + 0.1f * std::sin(5.0f * x) + noise * gauss(rng));
      }
    const auto add = [&](std::int64_t a, std::int64_t b, std::int64_t c) {
      if (a >= 0 && b >= 0 && c >= 0)
        in.triangles.push_back({static_cast<std::uint32_t>(a), static_cast<std::uint32_t>(b),
                                static_cast<std::uint32_t>(c)});
    };
    for (int j = 0; j + 1 < n; ++j)
      for (int i = 0; i + 1 < n; ++i) {
        const auto at = [&](int di, int dj) {
          return id[static_cast<std::size_t>((j + dj) * n + i + di)];
        };
        if (rng() % 2 == 0) {
          add(at(0, 0), at(1, 0), at(1, 1));
          add(at(0, 0), at(1, 1), at(0, 1));
        } else {
          add(at(0, 0), at(1, 0), at(0, 1));
          add(at(1, 0), at(1, 1), at(0, 1));
        }
      }
    for (float ratio : {0.05f, 0.25f, 0.6f}) {
      QemConfig config;
      config.target_ratio = ratio;
      // Independent collapses, or the walk's re-evaluations serial, in parallel chunks of 7
      // (many chunks) or of 256.
      config.independent_collapses = trial % 4 == 3;
      config.walk_chunk = static_cast<std::size_t>(trial % 4 == 0 ? 0 : trial % 4 == 1 ? 7 : 256);
      config.divide_by_depth2 = trial % 2 == 0;
      config.viewpoint = Eigen::Vector3f(0.5f, 0.5f, -1.0f);
      std::vector<TriangleMesh> out;
      for (int threads : {1, 2}) {
        ThreadLimit limit(threads);
        out.push_back(qem_decimate(in, config));
      }
      const MeshTopology topology = mesh_topology(out[0]);
      const std::string what =
          "trial " + std::to_string(trial) + ", ratio " + std::to_string(ratio) + ", chunk " +
          std::to_string(config.walk_chunk) + (config.independent_collapses ? ", independent" : "");
      EXPECT_LT(out[0].triangles.size(), in.triangles.size()) << what;
      EXPECT_EQ(topology.edges.non_manifold_edges, 0u) << what;
      EXPECT_EQ(topology.edges.inconsistent_edges, 0u) << what;
      EXPECT_EQ(topology.degenerate_faces, 0u) << what;
      EXPECT_EQ(out[0].triangles, out[1].triangles) << what;
    }
  }
}

// Hubs of 12 to 40 faces (fans of two to five blocks of eight in the vectorised checks), rings
// around them, and faces that repeat a vertex or repeat a face: decimated without a crash to a
// mesh whose corners are input vertices at their measured positions, as manifold as the
// well-formed part, the same with one and two threads.
TEST(QemDecimation, HubsAndRepeatedCornersAreHandled) {
  for (int spokes : {12, 17, 24, 40}) {
    TriangleMesh in;
    in.vertices.emplace_back(0.0f, 0.0f, 2.0f);  // the hub
    for (int ring = 1; ring <= 3; ++ring)
      for (int k = 0; k < spokes; ++k) {
        const double angle = 2.0 * 3.14159265358979 * (k + 0.5 * (ring % 2)) / spokes;
        const float r = 0.1f * static_cast<float>(ring);
        in.vertices.emplace_back(r * static_cast<float>(std::cos(angle)),
                                 r * static_cast<float>(std::sin(angle)),
                                 2.0f + 0.002f * static_cast<float>((k * 7 + ring) % 5));
      }
    const auto at = [spokes](int ring, int k) {
      return static_cast<std::uint32_t>(1 + (ring - 1) * spokes + (k % spokes + spokes) % spokes);
    };
    for (int k = 0; k < spokes; ++k) in.triangles.push_back({0, at(1, k), at(1, k + 1)});
    for (int ring = 1; ring < 3; ++ring)
      for (int k = 0; k < spokes; ++k) {
        // Rings alternate their half-step offset: inner k, k + 1 against outer k or k + 1.
        const int shift = ring % 2 == 1 ? 1 : 0;
        in.triangles.push_back({at(ring, k), at(ring + 1, k + shift), at(ring, k + 1)});
        in.triangles.push_back(
            {at(ring, k + 1), at(ring + 1, k + shift), at(ring + 1, k + shift + 1)});
      }
    const std::size_t well_formed = in.triangles.size();
    in.triangles.push_back({0, 0, at(1, 0)});                // a face repeating the hub
    in.triangles.push_back({at(2, 3), at(2, 4), at(2, 3)});  // and one repeating a ring vertex
    in.triangles.push_back(in.triangles[well_formed / 2]);   // a face given twice
    QemConfig config = plain_config();
    config.target_ratio = 0.3f;
    config.independent_collapses = spokes % 2 == 0;
    std::vector<TriangleMesh> out;
    for (int threads : {1, 2}) {
      ThreadLimit limit(threads);
      out.push_back(qem_decimate(in, config));
    }
    const std::string what = std::to_string(spokes) + " spokes";
    EXPECT_LT(out[0].triangles.size(), well_formed) << what;
    EXPECT_GT(out[0].triangles.size(), 0u) << what;
    EXPECT_EQ(out[0].triangles, out[1].triangles) << what;
    for (const Eigen::Vector3f& v : out[0].vertices)
      EXPECT_TRUE(std::find(in.vertices.begin(), in.vertices.end(), v) != in.vertices.end())
          << what;
    // The disc faces up; no collapse may turn a face by more than 60 degrees, so none of the
    // faces with an area points down.
    std::size_t up = 0;
    for (const Triangle& t : out[0].triangles) {
      for (std::uint32_t c : t) ASSERT_LT(c, out[0].vertices.size()) << what;
      const Eigen::Vector3f& a = out[0].vertices[t[0]];
      const Eigen::Vector3f n = (out[0].vertices[t[1]] - a).cross(out[0].vertices[t[2]] - a);
      EXPECT_GE(n.z(), 0.0f) << what;
      up += n.z() > 0.0f ? 1 : 0;
    }
    EXPECT_GE(up + 3, out[0].triangles.size()) << what;  // all but the repeated-corner faces
  }
}

// A noisy wave (about 29 k faces, a border) decimated to a quarter with independent
// collapses: the same mesh with one and two threads, manifold and consistently oriented, every
// face within 5 mm of the wave (centroids; the noise is 2 mm), no more faces standing on edge or
// turned against the wave's normal than the one-at-a-time walk leaves (both keep the measured,
// noisy vertices; KeepsMeasuredVerticesTopologyBorderAndNormals has none on a clean wave), and as
// close to the input as the walk (mean and p95 distance from the input's vertices, within 10 %:
// the two take their collapses in a slightly different order).
TEST(QemDecimation, IndependentCollapsesMatchTheWalkAndTheThreadCount) {
  std::mt19937 rng(11);
  std::normal_distribution<float> gauss(0.0f, 0.002f);
  TriangleMesh in = height_field(121, wave);
  for (Eigen::Vector3f& v : in.vertices) v.z() += gauss(rng);
  QemConfig config = plain_config();
  config.independent_collapses = true;
  std::vector<TriangleMesh> out;
  std::vector<QemReport> reports(2);
  for (int threads : {1, 2}) {
    ThreadLimit limit(threads);
    out.push_back(qem_decimate(in, config, &reports[static_cast<std::size_t>(threads - 1)]));
  }
  EXPECT_EQ(out[0].triangles, out[1].triangles);
  EXPECT_EQ(out[0].vertices, out[1].vertices);
  EXPECT_EQ(reports[0].passes, reports[1].passes);
  EXPECT_EQ(reports[0].rejected_topology, reports[1].rejected_topology);
  EXPECT_EQ(reports[0].rejected_normal, reports[1].rejected_normal);
  expect_quarter_with_one_border(in, out[0], "independent");
  EXPECT_GE(out[0].triangles.size(), in.triangles.size() / 4 - 2);
  config.independent_collapses = false;
  const TriangleMesh walked = qem_decimate(in, config);
  // {faces not facing along the wave's normal at their centroid, faces 5 mm or more off it}
  const auto off_the_wave = [](const TriangleMesh& m) {
    std::array<std::size_t, 2> off = {0, 0};
    for (const Triangle& t : m.triangles) {
      const Eigen::Vector3f& a = m.vertices[t[0]];
      const Eigen::Vector3f n = (m.vertices[t[1]] - a).cross(m.vertices[t[2]] - a);
      const Eigen::Vector3f c = (a + m.vertices[t[1]] + m.vertices[t[2]]) / 3.0f;
      off[0] += n.dot(wave_normal(c.x(), c.y())) > 0.0f ? 0 : 1;
      off[1] += std::abs(c.z() - wave(c.x(), c.y())) < 0.005f ? 0 : 1;
    }
    return off;
  };
  const auto off = off_the_wave(out[0]), off_walk = off_the_wave(walked);
  const DistanceStats independent = evaluate_surface(out[0], in).reference_to_mesh;
  const DistanceStats walk = evaluate_surface(walked, in).reference_to_mesh;
  std::printf(
      "[ qem ] independent collapses: %zu passes, mean %.3g p95 %.3g m, %zu faces on edge; "
      "walk %.3g %.3g m, %zu\n",
      reports[0].passes, independent.mean, independent.p95, off[0], walk.mean, walk.p95,
      off_walk[0]);
  EXPECT_LE(off[0], off_walk[0]);
  EXPECT_EQ(off[1], 0u);
  EXPECT_EQ(off_walk[1], 0u);
  EXPECT_LE(independent.mean, 1.1 * walk.mean);
  EXPECT_LE(independent.p95, 1.1 * walk.p95);
}

// A closed tetrahedron has no valid collapse (each would fold a face onto another), though
// every vertex has a finite cost bound: the pass that finds none and the one after it end the
// decimation, the mesh unchanged.
TEST(QemDecimation, NoValidCollapseEndsWithTheMeshUnchanged) {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  for (std::size_t walk_chunk : {std::size_t{0}, std::size_t{256}, std::size_t{1}}) {
    QemConfig config = plain_config();
    config.independent_collapses = walk_chunk == 1;  // (walk_chunk then does not matter)
    config.walk_chunk = walk_chunk;
    QemReport report;
    const TriangleMesh out = qem_decimate(m, config, &report);
    EXPECT_EQ(out.triangles, m.triangles) << "chunk " << walk_chunk;
    EXPECT_EQ(report.collapses, 0u);
    EXPECT_GT(report.rejected_normal + report.rejected_topology, 0u);
  }
}

// With borders allowed to turn sharply, ears (a border vertex of one face) collapse, but never
// the last face of a component: lone triangles and strips stay valid (was a write past a ring).
TEST(QemDecimation, EarsCollapseButNoComponentLosesItsLastFace) {
  TriangleMesh m = height_field(12, [](float x, float y) { return 0.05f * x * y; });
  for (int k = 0; k < 5; ++k) {  // lone triangles beside the grid
    const auto base = static_cast<std::uint32_t>(m.vertices.size());
    m.vertices.insert(m.vertices.end(),
                      {Eigen::Vector3f(2.0f + k, 0, 0), Eigen::Vector3f(2.5f + k, 0, 0),
                       Eigen::Vector3f(2.0f + k, 0.5f, 0)});
    m.triangles.push_back({base, base + 1, base + 2});
  }
  QemConfig config = plain_config();
  config.max_border_turn_deg = 180.0f;
  config.target_ratio = 0.01f;
  const TriangleMesh out = qem_decimate(m, config);
  EXPECT_GE(out.triangles.size(), 6u) << "each lone triangle and the grid keep a face";
  const EdgeStatistics e = edge_statistics(out);
  EXPECT_EQ(e.non_manifold_edges, 0u);
  EXPECT_EQ(e.inconsistent_edges, 0u);
}

// A face naming a vertex the mesh does not have is an error that names the face, not a read
// out of bounds.
TEST(QemDecimation, CornerOutOfRangeFailsNamingTheFace) {
  TriangleMesh m = height_field(4, [](float, float) { return 0.0f; });
  m.triangles[5][1] = static_cast<std::uint32_t>(m.vertices.size());
  try {
    qem_decimate(m);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.location(), "face 5");
    EXPECT_NE(std::string(e.what()).find("out of range (16 vertices)"), std::string::npos)
        << e.what();
  }
}

// Locked vertices (QemConfig::locked) are never removed, on the border or inside, while the
// rest still decimates (the wave with its whole border and every 5th vertex locked, recorded
// collapses: no locked u); no flags decimate as before, bit for bit; flags of another size
// than the vertices are an error.
TEST(QemDecimation, LockedVerticesAreNeverRemoved) {
  const TriangleMesh in = height_field(40, wave);
  QemConfig config = plain_config();
  config.record_collapses = true;
  const TriangleMesh free = qem_decimate(in, config);
  config.locked.assign(in.vertices.size(), 0);
  std::size_t locked = 0;
  for (std::size_t v = 0; v < in.vertices.size(); ++v) {
    const std::size_t i = v % 40, j = v / 40;
    if (i == 0 || j == 0 || i == 39 || j == 39 || v % 5 == 0) {
      config.locked[v] = 1;
      ++locked;
    }
  }
  QemReport report;
  const TriangleMesh out = qem_decimate(in, config, &report);
  EXPECT_GT(report.collapses, in.vertices.size() / 2) << "the rest decimates";
  for (const auto& [u, v] : report.collapse_sequence) EXPECT_EQ(config.locked[u], 0) << u;
  std::size_t kept = 0;  // output vertices are input vertices, in input order
  for (std::size_t v = 0, k = 0; v < in.vertices.size() && k < out.vertices.size(); ++v)
    if (in.vertices[v] == out.vertices[k]) {
      kept += config.locked[v];
      ++k;
    }
  EXPECT_EQ(kept, locked);
  EXPECT_EQ(edge_statistics(out).non_manifold_edges, 0u);
  EXPECT_EQ(mesh_topology(out).boundary_loops, 1u);
  config.locked.clear();
  const TriangleMesh unlocked = qem_decimate(in, config);
  EXPECT_EQ(unlocked.triangles, free.triangles);
  EXPECT_EQ(unlocked.vertices, free.vertices);
  config.locked.assign(in.vertices.size() - 1, 0);
  EXPECT_THROW(qem_decimate(in, config), Error);
}

}  // namespace
}  // namespace meshflow
