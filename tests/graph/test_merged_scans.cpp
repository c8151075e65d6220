// Several registered scans into one surface (run --merged): one sheet where scans overlap,
// manifold, as accurate as a single scan; the double-wall measure it is judged by.

#include "graph/merged_scans.h"

#include <gtest/gtest.h>

#include "nodes/eval/double_walls.h"
#include "nodes/eval/surface_eval.h"
#include "nodes/io/sequence.h"
#include "nodes/synthetic/scan_sequence.h"
#include "test_support.h"

namespace meshflow {
namespace {

TEST(DoubleWalls, OneSheetNoneTwoCopiesAllTwoSidesNone) {
  const TriangleMesh grid = test::grid_mesh(20);  // unit spacing
  EXPECT_EQ(double_wall_area_share(grid, 0.5f), 0.0);
  TriangleMesh two = grid;  // a copy 0.3 above, facing the same way
  const auto n = static_cast<std::uint32_t>(grid.vertices.size());
  for (const Eigen::Vector3f& v : grid.vertices)
    two.vertices.push_back(v + Eigen::Vector3f(0, 0, 0.3f));
  for (const Triangle& t : grid.triangles) two.triangles.push_back({t[0] + n, t[1] + n, t[2] + n});
  EXPECT_NEAR(double_wall_area_share(two, 0.5f), 1.0, 1e-9);
  EXPECT_EQ(double_wall_area_share(two, 0.2f), 0.0) << "farther apart than the radius";
  TriangleMesh sides = two;  // the copy turned over: the two sides of a thin wall
  for (std::size_t t = grid.triangles.size(); t < sides.triangles.size(); ++t)
    std::swap(sides.triangles[t][1], sides.triangles[t][2]);
  EXPECT_EQ(double_wall_area_share(sides, 0.5f), 0.0);
}

// Frames of a sequence through the preparation graph, joined; then one reconstruction.
struct Merged {
  FramePtr frame;
  std::size_t frames = 0;
};

Merged merge_and_reconstruct(const io::Sequence& sequence, const ReconstructionConfig& config) {
  ScanPreparationPipeline preparation(config, 2);
  Merged m;
  PointCloud joined;
  run_sequence(preparation, sequence, {}, [&](const Frame& f) {
    ASSERT_TRUE(f.ok()) << f.error;
    ASSERT_EQ(f.cloud.normals.size(), f.cloud.size());
    append_scan(joined, f.cloud);
    ++m.frames;
  });
  m.frame = ReconstructionPipeline(merged_pass_config(config)).reconstruct(std::move(joined));
  return m;
}

TriangleMesh concatenated_meshes(const io::Sequence& sequence, const ReconstructionConfig& config) {
  ReconstructionPipeline pipeline(config, 2);
  TriangleMesh all;
  run_sequence(pipeline, sequence, {}, [&](const Frame& f) {
    const auto offset = static_cast<std::uint32_t>(all.vertices.size());
    all.vertices.insert(all.vertices.end(), f.mesh.vertices.begin(), f.mesh.vertices.end());
    for (const Triangle& t : f.mesh.triangles)
      all.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  });
  return all;
}

TEST(MergedScans, SyntheticScansGiveOneSheetWithinAQuarterVoxel) {
  const synthetic::Scene scene = synthetic::demo_room_scene();
  synthetic::ScanSequenceConfig sc;
  sc.frames = 3;
  sc.scan.azimuth_steps = 240;
  sc.scan.elevation_steps = 80;
  const auto sequence = synthetic::make_scan_sequence(scene, sc);
  ReconstructionConfig config;
  const float voxel = 0.05f;
  config.voxelize.voxel_size = voxel;
  const Merged merged = merge_and_reconstruct(*sequence, config);
  ASSERT_TRUE(merged.frame->ok()) << merged.frame->error;
  EXPECT_EQ(merged.frames, 3u);
  const TriangleMesh& mesh = merged.frame->mesh;
  const double walls = double_wall_area_share(mesh, 0.5f * voxel);
  const double concatenated_walls =
      double_wall_area_share(concatenated_meshes(*sequence, config), 0.5f * voxel);
  std::printf("[ merged ] double walls %.2f %% (per-scan meshes side by side: %.2f %%)\n",
              100 * walls, 100 * concatenated_walls);
  EXPECT_LT(walls, 0.01);
  EXPECT_GT(concatenated_walls, 0.2) << "the measure sees the sheets of side-by-side meshes";
  EXPECT_EQ(mesh_topology(mesh).edges.non_manifold_edges, 0u);
  const auto err = test::vertex_errors(
      mesh, [&](const Eigen::Vector3f& p) { return synthetic::surface_distance(scene, p); });
  EXPECT_LT(err.mean, 0.25 * voxel);
  EXPECT_EQ(merged.frame->normals.estimated, 0u) << "the joined cloud keeps its per-scan normals";
}

TEST(MergedScans, Kurt3dThreeScansOneManifoldSurface) {
  MESHFLOW_REQUIRE_DATA("kurt3d/scan002.3d");
  const auto sequence = io::open_sequence(test::data_path("kurt3d"));
  ReconstructionConfig config;
  const float voxel = 0.05f;
  config.voxelize.voxel_size = voxel;
  const Merged merged = merge_and_reconstruct(*sequence, config);
  ASSERT_TRUE(merged.frame->ok()) << merged.frame->error;
  const TriangleMesh& mesh = merged.frame->mesh;
  const MeshTopology topology = mesh_topology(mesh);
  const double walls = double_wall_area_share(mesh, 0.5f * voxel);
  std::printf("[ kurt3d merged ] %zu points -> %zu triangles, double walls %.2f %%\n",
              merged.frame->filter_counts.input, mesh.triangles.size(), 100 * walls);
  EXPECT_EQ(topology.edges.non_manifold_edges, 0u);
  EXPECT_EQ(topology.edges.inconsistent_edges, 0u);
  EXPECT_LT(walls, 0.01);
}

}  // namespace
}  // namespace meshflow
