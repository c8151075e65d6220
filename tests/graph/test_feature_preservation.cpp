// Sharp edges through the reducing optimize lists (issue 59): CAD-like closed objects scanned
// without a sensor (voxel = 1 % of the diagonal, extended marching cubes), then each list with
// the feature graph (--feature-angle 40, the default) and without (180). Truth: the objects'
// exact distance, their true edges and corners.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "graph/pipeline.h"
#include "nodes/eval/truth_eval.h"
#include "nodes/optimize/features.h"
#include "nodes/synthetic/closed_objects.h"

namespace meshflow {
namespace {

struct FeatureScore {
  std::size_t triangles = 0;
  double mean = 0.0, p95 = 0.0;  ///< area-sampled distance to the true surface, metres
  /// Points every quarter voxel along the true edges: the share within 0.25 voxel of a sharp
  /// mesh edge, and the 95th percentile of that distance (voxels).
  double covered = 0.0, edge_p95 = 0.0;
  double corner_max = 0.0;  ///< largest distance of a true corner to a mesh vertex, voxels
};

float segment_distance(const Eigen::Vector3f& p, const Eigen::Vector3f& a,
                       const Eigen::Vector3f& b) {
  const Eigen::Vector3f ab = b - a;
  const float t = std::clamp((p - a).dot(ab) / std::max(ab.squaredNorm(), 1e-30f), 0.0f, 1.0f);
  return (a + t * ab - p).norm();
}

// Points every quarter voxel along the object's true edges: the share within 0.25 voxel of an
// edge of `f` (a feature graph of `mesh`), and the 95th percentile of that distance (voxels).
void edge_coverage(const TriangleMesh& mesh, const MeshFeatures& f,
                   const synthetic::ClosedObject& object, float voxel, FeatureScore& s) {
  std::vector<float> d;
  for (const auto& [a, b] : object.feature_edges) {
    const int steps = std::max(1, static_cast<int>((b - a).norm() / (0.25f * voxel)));
    for (int i = 0; i <= steps; ++i) {
      const Eigen::Vector3f p = a + (b - a) * (static_cast<float>(i) / static_cast<float>(steps));
      float best = std::numeric_limits<float>::infinity();
      for (const auto& edge : f.edges)
        best = std::min(best, segment_distance(p, mesh.vertices[edge[0]], mesh.vertices[edge[1]]));
      d.push_back(best / voxel);
    }
  }
  if (!d.empty()) {
    s.covered =
        static_cast<double>(std::count_if(d.begin(), d.end(), [](float x) { return x <= 0.25f; })) /
        static_cast<double>(d.size());
    std::sort(d.begin(), d.end());
    s.edge_p95 = d[d.size() * 95 / 100];
  }
}

FeatureScore score(const TriangleMesh& mesh, const synthetic::ClosedObject& object, float voxel) {
  FeatureScore s;
  s.triangles = mesh.triangles.size();
  const TruthEvaluation e = evaluate_against_truth(
      mesh, [&object](const Eigen::Vector3f& p) { return object.distance(p); }, 50000);
  s.mean = e.area.mean;
  s.p95 = e.area.p95;
  // Every sharp edge counts (no line dropped as noise: these meshes have none, and a reduced
  // mesh's few long edges make short lines).
  edge_coverage(mesh, detect_features(mesh, kDefaultFeatureAngleDeg, -1.0f), object, voxel, s);
  for (const Eigen::Vector3f& c : object.corners) {
    float best = std::numeric_limits<float>::infinity();
    for (const Eigen::Vector3f& v : mesh.vertices) best = std::min(best, (v - c).norm());
    s.corner_max = std::max(s.corner_max, static_cast<double>(best / voxel));
  }
  return s;
}

// The extraction, and extended marching cubes' feature vertices (what the frame hands the
// optimize stage).
struct RawMesh {
  TriangleMesh mesh;
  std::vector<std::uint8_t> feature_vertices;
};

RawMesh raw_mesh(const synthetic::ClosedObject& object, float voxel) {
  ReconstructionConfig c;
  c.voxelize.voxel_size = voxel;
  c.optimize.steps.clear();
  PointCloud cloud = object.sample(100000, 0.0f, 59);
  cloud.normals.clear();
  FramePtr f = ReconstructionPipeline(c).reconstruct(std::move(cloud));
  EXPECT_TRUE(f->ok()) << f->error;
  EXPECT_EQ(f->extract_method, ExtractMethod::kExtendedMarchingCubes);
  EXPECT_EQ(f->feature_vertices.size(), f->mesh.vertices.size());  // no step: still the mesh's
  return {f->mesh, f->feature_vertices};
}

TriangleMesh optimized(const TriangleMesh& mesh, const std::string& list, float voxel,
                       float feature_angle, const std::vector<std::uint8_t>* seed = nullptr) {
  ReconstructionConfig c;
  c.voxelize.voxel_size = voxel;
  c.optimize.steps = parse_optimize_steps(list);
  c.optimize.feature_angle_deg = feature_angle;
  const OptimizeConfig config = optimize_config_for_voxel(c, voxel);
  return seed ? optimize_mesh(mesh, config, nullptr, *seed) : optimize_mesh(mesh, config);
}

void print(const char* what, const FeatureScore& s) {
  std::printf(
      "[ features ] %-40s %7zu triangles, mean %.2e p95 %.2e m, edges covered %5.1f %% (p95 "
      "%.3f voxel), corners max %.3f voxel\n",
      what, s.triangles, s.mean, s.p95, 100.0 * s.covered, s.edge_p95, s.corner_max);
}

class FeaturePreservation : public ::testing::TestWithParam<const char*> {};

TEST_P(FeaturePreservation, ReducingListsKeepEdgesCornersAndAccuracy) {
  const synthetic::ClosedObject object = *synthetic::closed_test_object(GetParam());
  const float voxel = 0.01f * object.diagonal();
  // The float step (ulp) at the object's largest coordinate: positions are rounded to it.
  const float extent = std::max(object.bounds.min().cwiseAbs().maxCoeff(),
                                object.bounds.max().cwiseAbs().maxCoeff());
  const double float_step =
      static_cast<double>(std::nextafter(extent, std::numeric_limits<float>::infinity()) - extent);
  const RawMesh extracted = raw_mesh(object, voxel);
  const TriangleMesh& raw = extracted.mesh;
  const std::vector<std::uint8_t>& seed = extracted.feature_vertices;
  const FeatureScore before = score(raw, object, voxel);
  print((object.name + " raw").c_str(), before);
  {  // the graph seeded from EMC's feature vertices covers the true edges detection covers
    FeatureScore seeded;
    edge_coverage(raw, detect_features(raw, seed), object, voxel, seeded);
    FeatureScore detected;
    edge_coverage(raw, detect_features(raw), object, voxel, detected);
    std::printf(
        "[ features ] %-40s edges covered seeded %5.1f %% (p95 %.3f voxel), detected "
        "%5.1f %% (p95 %.3f voxel)\n",
        (object.name + " graph").c_str(), 100.0 * seeded.covered, seeded.edge_p95,
        100.0 * detected.covered, detected.edge_p95);
    // The flags only add edges (at a lower angle): the seeded graph covers at least as much.
    EXPECT_GE(seeded.covered, detected.covered);
    EXPECT_LE(seeded.edge_p95, detected.edge_p95);
  }
  {  // clean and holes alone reduce nothing and keep every feature where it was
    const FeatureScore kept =
        score(optimized(raw, "clean,holes", voxel, kDefaultFeatureAngleDeg), object, voxel);
    print((object.name + " clean,holes").c_str(), kept);
    EXPECT_GE(kept.covered, before.covered);
    EXPECT_LE(kept.corner_max, before.corner_max);
    EXPECT_LE(kept.mean, 1.1 * before.mean);  // a few small holes filled: other samples
  }
  for (const char* list : {"clean,holes,remesh", "clean,holes,planes,retriangulate", "decimate"}) {
    const FeatureScore without = score(optimized(raw, list, voxel, 180.0f), object, voxel);
    print((object.name + " " + list + " (no features)").c_str(), without);
    // The graph seeded from EMC's feature vertices (the pipeline), and detected (a mesh from
    // another tool: `meshflow optimize`).
    for (const bool seeded : {true, false}) {
      SCOPED_TRACE(std::string(list) + (seeded ? " seeded" : " detected"));
      const FeatureScore with =
          score(optimized(raw, list, voxel, kDefaultFeatureAngleDeg, seeded ? &seed : nullptr),
                object, voxel);
      print((object.name + " " + list + (seeded ? " (seeded)" : " (detected)")).c_str(), with);
      const bool planar_list = std::string(list).find("planes") != std::string::npos;
      const bool cad = object.name != "torus";
      if (!object.feature_edges.empty()) {
        // Every true edge still on sharp mesh edges, the corners where the extraction put them
        // (EMC itself leaves them up to 0.37 voxel off on the L-shape and the chamfered cube).
        EXPECT_GE(with.covered, std::min(0.95, before.covered));  // plain QEM: 96.6 %
        EXPECT_LE(with.edge_p95, 0.25);
        EXPECT_LE(with.corner_max, before.corner_max + 0.05);
      }
      // Accuracy within 1.25 x the unreduced mesh (issue 59's bar; the remesh keeps a clean
      // extraction's accuracy on the cylinder too), or within 0.0002 voxel of it: EMC's faces
      // are exact to 1e-7 m, the mean is a few stray spots, and 50 000 samples measure it to
      // about 15 %. The planar list holds the p95 too (measured 0.95-1.01x: its planes are exact
      // and the box with a hole's cylinder is left curved; was 300-2300x the raw p95 and
      // 2.5-11x its mean when planes were fitted through every vertex within --plane-tolerance).
      const bool curved = !cad;
      if (cad && !planar_list) {
        EXPECT_LE(with.mean, std::max(1.25 * before.mean, before.mean + 0.0002 * voxel));
      }
      if (cad && list == std::string("clean,holes,remesh")) {
        // The remesh holds the p95 too once feature vertices move onto their sides' planes only
        // where those planes are known better than the vertex lies on them (was 18x, the
        // chamfered cube 1.96x). The floor is float rounding, not 0.0002 voxel (that would pass
        // 18x): EMC's faces are exact, their p95 (6.7e-8 m) is 2.2 float steps at the objects'
        // largest coordinate (0.4 m, a step of 3.0e-8 m); the remesh's new vertices, projected
        // onto the input in float, lie a step or two farther (the L-shape 1.2e-7 m, 4 steps: the
        // "1.76x" measured before was that).
        EXPECT_LE(with.p95, std::max(1.25 * before.p95, 8.0 * float_step));
      } else if (planar_list && !curved) {
        EXPECT_LE(with.mean, std::max(1.25 * before.mean, before.mean + 0.0002 * voxel));
        EXPECT_LE(with.p95, std::max(1.25 * before.p95, before.p95 + 0.0002 * voxel));
      }
      if (!planar_list) {
        // Features cost no accuracy worth measuring (at most 0.001 voxel of mean error).
        EXPECT_LE(with.mean, std::max(1.05 * without.mean, without.mean + 0.001 * voxel));
      }
      if (cad) {
        EXPECT_LE(with.triangles, before.triangles / 2);
      } else {  // smooth: the same reduction as without features
        EXPECT_LE(with.triangles, without.triangles + without.triangles / 100);
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Objects, FeaturePreservation,
                         ::testing::Values("box", "l-shape", "chamfered-cube", "box-with-hole",
                                           "torus"));

}  // namespace
}  // namespace meshflow
