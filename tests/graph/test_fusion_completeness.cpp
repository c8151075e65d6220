// Fused maps against exact truth: a depth camera circling meshflow's closed test objects
// (synthetic::make_object_orbit), written as a TUM RGB-D directory and fused back through the
// flow graph — completeness (truth -> mesh) and accuracy (mesh -> truth) of the default band
// behind the surface against the symmetric band of KinectFusion / Open3D.

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdio>
#include <utility>

#include "graph/fusion_pipeline.h"
#include "graph/sequence_runner.h"
#include "nodes/eval/surface_eval.h"
#include "nodes/eval/truth_eval.h"
#include "nodes/io/sequence.h"
#include "nodes/io/tum_writer.h"
#include "nodes/search/mesh_distance_index.h"
#include "nodes/synthetic/depth_sequence.h"
#include "nodes/synthetic/object_orbit.h"
#include "nodes/synthetic/perforated_box.h"
#include "test_support.h"

namespace meshflow {
namespace {

struct FusedFigures {
  double accuracy = 0.0;      ///< mesh -> truth, mean, fraction of the diagonal
  double completeness = 0.0;  ///< truth -> mesh, mean, fraction of the diagonal
  TriangleMesh mesh;
};

// Fuses `sequence` at 1 cm with the given band behind the surface and measures the mesh.
FusedFigures fuse_and_measure(const io::Sequence& sequence, const synthetic::ClosedObject& object,
                              float behind_voxels, bool subpixel_depth = true,
                              TsdfIntegrator integrator = TsdfIntegrator::kProjective) {
  FusionConfig config;
  config.tsdf.voxel_size = 0.01f;
  config.tsdf.behind_voxels = behind_voxels;
  config.tsdf.subpixel_depth = subpixel_depth;
  config.tsdf.integrator = integrator;
  FusionPipeline pipeline(config, 2);
  const SequenceRunStats stats =
      run_sequence(pipeline, sequence, {}, [](const Frame& f) { ASSERT_TRUE(f.ok()) << f.error; });
  EXPECT_EQ(stats.frames_ok, sequence.size());
  FusedFigures out;
  out.mesh = pipeline.extract_mesh();
  const double diagonal = object.diagonal();
  out.accuracy = evaluate_against_truth(
                     out.mesh, [&](const Eigen::Vector3f& p) { return object.distance(p); }, 50000)
                     .area.mean /
                 diagonal;
  TriangleMesh truth;
  truth.vertices = object.sample(50000, 0.0f, 7).positions;
  out.completeness = evaluate_surface(out.mesh, truth).reference_to_mesh.mean / diagonal;
  return out;
}

std::unique_ptr<io::Sequence> small_orbit(const synthetic::ClosedObject& object) {
  synthetic::ObjectOrbitConfig c;
  c.frames = 12;
  c.intrinsics = synthetic::scaled_default_camera(320, 240);
  return synthetic::make_object_orbit(object, c);
}

// The object's orbit fused with the default band and with the symmetric one, both printed.
std::pair<FusedFigures, FusedFigures> default_and_symmetric_band(
    const synthetic::ClosedObject& object) {
  const auto orbit = small_orbit(object);
  FusedFigures band = fuse_and_measure(*orbit, object, TsdfConfig{}.behind_voxels);
  FusedFigures symmetric = fuse_and_measure(*orbit, object, TsdfConfig{}.truncation_voxels);
  std::printf("[ %s ] default band: accuracy %.2e completeness %.2e; symmetric: %.2e %.2e\n",
              object.name.c_str(), band.accuracy, band.completeness, symmetric.accuracy,
              symmetric.completeness);
  return {std::move(band), std::move(symmetric)};
}

TEST(FusionCompleteness, ThinPlateKeepsBothSidesWithTheShortBand) {
  // A 2 cm plate at 1 cm voxels and a 4 cm truncation: the symmetric band lets each side's
  // views overwrite the other side (the plate thins and tears); the default band keeps it.
  const auto [band, symmetric] = default_and_symmetric_band(synthetic::thin_plate_object());
  EXPECT_LT(band.completeness, 0.4 * symmetric.completeness);
  EXPECT_LT(band.accuracy, 0.5 * symmetric.accuracy);
  EXPECT_LT(band.completeness, 2e-3);
}

// The share of `truth` within `tau` metres of the mesh's surface. Parallel; O(truth x log).
double share_within(const TriangleMesh& mesh, const std::vector<Eigen::Vector3f>& truth,
                    float tau) {
  const MeshDistanceIndex index(mesh);
  std::vector<std::uint8_t> near(truth.size());
  tbb::parallel_for(std::size_t{0}, truth.size(), [&](std::size_t i) {
    near[i] = index.closest(truth[i]).distance <= tau ? 1 : 0;
  });
  return static_cast<double>(std::count(near.begin(), near.end(), 1)) /
         static_cast<double>(truth.size());
}

// The pocketed block (perforated_box.h) seen by 24 views on the orbit at 320 x 240, fused with
// the default band and with the symmetric one by `integrator`: the share of the truth within
// half a voxel of each mesh and their accuracy and completeness, printed.
struct ConcaveFigures {
  FusedFigures band, symmetric;
  double half_voxel = 0.0, half_voxel_symmetric = 0.0;
};
ConcaveFigures pocketed_block_figures(TsdfIntegrator integrator) {
  const synthetic::ClosedObject block = synthetic::pocketed_block_object();
  synthetic::ObjectOrbitConfig c;
  c.frames = 24;
  c.intrinsics = synthetic::scaled_default_camera(320, 240);
  const auto orbit = synthetic::make_object_orbit(block, c);
  ConcaveFigures out;
  out.band = fuse_and_measure(*orbit, block, TsdfConfig{}.behind_voxels, true, integrator);
  out.symmetric = fuse_and_measure(*orbit, block, TsdfConfig{}.truncation_voxels, true, integrator);
  const std::vector<Eigen::Vector3f> truth = block.sample(50000, 0.0f, 11).positions;
  out.half_voxel = share_within(out.band.mesh, truth, 0.005f);
  out.half_voxel_symmetric = share_within(out.symmetric.mesh, truth, 0.005f);
  std::printf(
      "[ %s, %s ] within half a voxel %.4f, accuracy %.2e, completeness %.2e; symmetric band "
      "%.4f, %.2e, %.2e\n",
      block.name.c_str(), integrator == TsdfIntegrator::kAlongRay ? "along rays" : "projective",
      out.half_voxel, out.band.accuracy, out.band.completeness, out.half_voxel_symmetric,
      out.symmetric.accuracy, out.symmetric.completeness);
  return out;
}

TEST(FusionCompleteness, ConcaveObjectKeepsTheWallsOfItsHoles) {
  // A block drilled with three blind pockets, a through hole and a side hole. Their walls are
  // seen at grazing angles, their floors hardly at all: about 15 % of the surface is never seen.
  // The band's widening on slanted surfaces reaches only voxels no frame observed, so a grazing
  // view of one wall does not overwrite the opposite wall; measured 0.838 of the surface within
  // half a voxel (Open3D 0.808 on the same frames, bench/peers/fusion_vs_open3d.cpp) and
  // accuracy 5.8e-4 of the diagonal (Open3D 1.6e-3). The symmetric band (Open3D's) is both less
  // complete and less accurate.
  const ConcaveFigures f = pocketed_block_figures(TsdfIntegrator::kProjective);
  EXPECT_GT(f.half_voxel, 0.83);
  EXPECT_GT(f.half_voxel, f.half_voxel_symmetric + 0.02);
  EXPECT_LT(f.band.accuracy, 7e-4);
  EXPECT_LT(f.band.accuracy, 0.5 * f.symmetric.accuracy);
  EXPECT_LT(f.band.completeness, f.symmetric.completeness);
}

TEST(FusionCompleteness, AlongRayConcaveObjectKeepsTheWallsOfItsHoles) {
  // The along-ray integrator holds observed voxels to the same band as the projective one: its
  // merged rays' band widens on slanted surfaces only over voxels no frame observed. Measured:
  // accuracy 7.16e-4 of the diagonal, 0.8459 of the surface within half a voxel (widened band
  // over observed voxels too, as before: 8.38e-4, 0.8454; symmetric band 1.62e-3, 0.8147).
  const ConcaveFigures f = pocketed_block_figures(TsdfIntegrator::kAlongRay);
  EXPECT_LT(f.band.accuracy, 7.7e-4);
  EXPECT_GT(f.half_voxel, 0.84);
  EXPECT_GT(f.half_voxel, f.half_voxel_symmetric + 0.02);
  EXPECT_LT(f.band.accuracy, 0.5 * f.symmetric.accuracy);
  EXPECT_LT(f.band.completeness, f.symmetric.completeness);
}

TEST(FusionCompleteness, SharpEdgedObjectIsAsCompleteAndMoreAccurate) {
  const auto [band, symmetric] = default_and_symmetric_band(synthetic::l_shape_object());
  EXPECT_LE(band.completeness, symmetric.completeness);
  EXPECT_LT(band.accuracy, 0.7 * symmetric.accuracy);
  const EdgeStatistics edges = edge_statistics(band.mesh);
  EXPECT_EQ(edges.boundary_edges, 0u);  // watertight
  EXPECT_EQ(edges.non_manifold_edges, 0u);
}

TEST(FusionCompleteness, SubpixelDepthBeatsTheNearestPixelOnASmoothObject) {
  // The nearest pixel's depth is off by up to half a pixel's depth step wherever the surface is
  // slanted; correcting it by the depth slope to the voxel's exact projection removes most of
  // that error (accuracy / completeness 3.5e-4 / 3.3e-4 against 5.7e-4 / 5.4e-4).
  const synthetic::ClosedObject sphere = synthetic::sphere_object();
  const auto orbit = small_orbit(sphere);
  const FusedFigures subpixel = fuse_and_measure(*orbit, sphere, TsdfConfig{}.behind_voxels);
  const FusedFigures nearest = fuse_and_measure(*orbit, sphere, TsdfConfig{}.behind_voxels, false);
  std::printf("[ sphere ] subpixel depth: %.2e / %.2e; nearest pixel: %.2e / %.2e\n",
              subpixel.accuracy, subpixel.completeness, nearest.accuracy, nearest.completeness);
  EXPECT_LT(subpixel.accuracy, 0.75 * nearest.accuracy);
  EXPECT_LT(subpixel.completeness, 0.75 * nearest.completeness);
  EXPECT_EQ(edge_statistics(subpixel.mesh).boundary_edges, 0u);
}

TEST(FusionCompleteness, TumDirectoryRoundTripFusesLikeTheFramesInMemory) {
  // The orbit written as a TUM RGB-D directory (16-bit depth at 1/5000 m, colour, poses) and
  // read back: the same mesh within the depth quantisation, with the frames' colours.
  const synthetic::ClosedObject torus = synthetic::torus_object();
  const auto orbit = small_orbit(torus);
  const std::string dir = test::temp_dir() + "/torus_tum";
  io::write_tum_directory(*orbit, dir);
  const auto from_disk = io::open_sequence(dir);
  ASSERT_EQ(from_disk->size(), orbit->size());
  const FusedFigures memory = fuse_and_measure(*orbit, torus, TsdfConfig{}.behind_voxels);
  const FusedFigures disk = fuse_and_measure(*from_disk, torus, TsdfConfig{}.behind_voxels);
  std::printf("[ torus ] in memory: %.2e / %.2e; from TUM files: %.2e / %.2e\n", memory.accuracy,
              memory.completeness, disk.accuracy, disk.completeness);
  EXPECT_NEAR(disk.accuracy, memory.accuracy, 0.1 * memory.accuracy);
  EXPECT_NEAR(disk.completeness, memory.completeness, 0.1 * memory.completeness);
  EXPECT_EQ(edge_statistics(disk.mesh).boundary_edges, 0u);
  // The frames shade the surface by its outward normal (rgb = 127.5 (n + 1)): the fused colours
  // follow the mesh's own normals.
  ASSERT_EQ(disk.mesh.colors.size(), disk.mesh.vertices.size());
  ASSERT_EQ(disk.mesh.normals.size(), disk.mesh.vertices.size());
  double error = 0.0;
  for (std::size_t i = 0; i < disk.mesh.vertices.size(); ++i) {
    const Eigen::Vector3f n = disk.mesh.normals[i].normalized();
    const Rgb8 c = disk.mesh.colors[i];
    error += std::abs(c.r - 127.5 * (n.x() + 1)) + std::abs(c.g - 127.5 * (n.y() + 1)) +
             std::abs(c.b - 127.5 * (n.z() + 1));
  }
  error /= 3.0 * static_cast<double>(disk.mesh.vertices.size());
  std::printf("[ torus ] mean colour error against the normal shading: %.1f of 255\n", error);
  EXPECT_LT(error, 12.0);
}

// --fuse on every kind of sequence in the shared data: Redwood (trajectory.log), the Kinect
// grabber's organized PCDs, and its depth-image directories (PCLZF and TIFF, camera frame).
TEST(FusionCompleteness, EverySharedSequenceKindFusesWithColour) {
  MESHFLOW_REQUIRE_DATA("kinect_pcl/grabber_sequences/tiff");
  for (const char* path :
       {"rgbd_redwood", "kinect_pcl/grabber_sequences/pcd", "kinect_pcl/grabber_sequences/pclzf",
        "kinect_pcl/grabber_sequences/tiff"}) {
    const auto sequence = io::open_sequence(test::data_path(path));
    FusionConfig config;
    config.tsdf.voxel_size = 0.01f;
    FusionPipeline pipeline(config, 2);
    const SequenceRunStats stats = run_sequence(pipeline, *sequence, {}, [&](const Frame& f) {
      EXPECT_TRUE(f.ok()) << path << ": " << f.error;
    });
    EXPECT_EQ(stats.frames_ok, sequence->size()) << path;
    const TriangleMesh mesh = pipeline.extract_mesh();
    std::printf("[ %s ] %zu frames, %zu triangles\n", path, sequence->size(),
                mesh.triangles.size());
    EXPECT_GT(mesh.triangles.size(), 20000u) << path;
    EXPECT_EQ(mesh.colors.size(), mesh.vertices.size()) << path;
    EXPECT_EQ(edge_statistics(mesh).non_manifold_edges, 0u) << path;
  }
}

}  // namespace
}  // namespace meshflow
