// Closed objects scanned as a turntable or handheld scanner scans them (a few views on one ring,
// the underside unseen, 1 mm range noise, 0.5 % outliers scattered in the bounding box, merged
// into one cloud without normals or sensor), meshed by the default pipeline.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <numeric>

#include "graph/pipeline.h"
#include "nodes/synthetic/closed_objects.h"
#include "nodes/synthetic/object_scan.h"
#include "test_support.h"

namespace meshflow {
namespace {

// Triangles joined by shared vertices: each component's triangle indices.
std::vector<std::vector<std::size_t>> mesh_components(const TriangleMesh& mesh) {
  std::vector<std::uint32_t> parent(mesh.vertices.size());
  std::iota(parent.begin(), parent.end(), 0u);
  const auto root = [&](std::uint32_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (const Triangle& t : mesh.triangles)
    for (int e = 1; e < 3; ++e) {
      const std::uint32_t a = root(t[0]), b = root(t[static_cast<std::size_t>(e)]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  std::vector<int> id(mesh.vertices.size(), -1);
  std::vector<std::vector<std::size_t>> out;
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    const std::uint32_t r = root(mesh.triangles[i][0]);
    if (id[r] < 0) {
      id[r] = static_cast<int>(out.size());
      out.emplace_back();
    }
    out[static_cast<std::size_t>(id[r])].push_back(i);
  }
  return out;
}

// Median distance of a component's vertices to the exact surface, metres.
float median_surface_distance(const TriangleMesh& mesh, const std::vector<std::size_t>& component,
                              const synthetic::ClosedObject& object) {
  std::vector<float> d;
  for (std::size_t t : component)
    for (std::uint32_t v : mesh.triangles[t]) d.push_back(object.distance(mesh.vertices[v]));
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  return d[d.size() / 2];
}

synthetic::ObjectScan scanned(const synthetic::ClosedObject& object, std::uint32_t seed) {
  synthetic::ObjectScanConfig sc;
  sc.outlier_fraction = 0.005f;
  sc.seed = seed;
  return synthetic::scan_object(object, sc);
}

ReconstructionConfig scan_config(const synthetic::ClosedObject& object) {
  ReconstructionConfig c;
  c.voxelize.voxel_size = 0.01f * object.diagonal();
  return c;
}

// Components of the mesh whose vertices lie mostly away from the object (made of outliers).
std::size_t outlier_components(const TriangleMesh& mesh, const synthetic::ClosedObject& object,
                               float voxel) {
  std::size_t count = 0;
  for (const auto& component : mesh_components(mesh))
    count += median_surface_distance(mesh, component, object) > voxel ? 1 : 0;
  return count;
}

class ScannedObject : public ::testing::TestWithParam<int> {
 protected:
  synthetic::ClosedObject object() const {
    return synthetic::closed_test_objects()[static_cast<std::size_t>(GetParam())];
  }
};

TEST_P(ScannedObject, NoComponentMadeOfOutliers) {
  const synthetic::ClosedObject object = this->object();
  const synthetic::ObjectScan scan = scanned(object, 31);
  ReconstructionConfig config = scan_config(object);
  const float voxel = config.voxelize.voxel_size;
  const FramePtr f = ReconstructionPipeline(config).reconstruct(scan.cloud);
  ASSERT_TRUE(f->ok()) << f->error;
  EXPECT_EQ(outlier_components(f->mesh, object, voxel), 0u);
  const std::size_t dropped = f->filter_counts.isolated + f->filter_counts.sparse_clusters;
  const std::size_t surface = scan.cloud.size() - scan.outliers;
  EXPECT_GT(dropped, scan.outliers / 2);
  // Besides outliers, only the last rows seen at grazing angles (sparser than a link) go.
  EXPECT_LE(dropped, scan.outliers + surface / 200);
  std::printf("[ outliers ] %s: %zu dropped (%zu isolated) of %zu points with %zu outliers\n",
              object.name.c_str(), dropped, f->filter_counts.isolated, scan.cloud.size(),
              scan.outliers);

  // Without the clean step too, the removal alone leaves no component of outliers.
  config.optimize.steps.clear();
  const FramePtr raw = ReconstructionPipeline(config).reconstruct(scan.cloud);
  ASSERT_TRUE(raw->ok()) << raw->error;
  EXPECT_EQ(outlier_components(raw->mesh, object, voxel), 0u);
}

TEST(ScannedObjects, WithoutTheRemovalOutliersMakeComponents) {
  // What the default removes upstream of the mesh: with --outlier-cluster 0 and no clean step,
  // the same scans give components made of outliers.
  std::size_t components = 0;
  for (const synthetic::ClosedObject& object : synthetic::closed_test_objects()) {
    ReconstructionConfig config = scan_config(object);
    config.optimize.steps.clear();
    config.filter.outlier_cluster = 0;
    const FramePtr off = ReconstructionPipeline(config).reconstruct(scanned(object, 31).cloud);
    ASSERT_TRUE(off->ok()) << off->error;
    EXPECT_EQ(off->filter_counts.isolated + off->filter_counts.sparse_clusters, 0u);
    components += outlier_components(off->mesh, object, config.voxelize.voxel_size);
  }
  EXPECT_GT(components, 0u);
}

INSTANTIATE_TEST_SUITE_P(Objects, ScannedObject, ::testing::Range(0, 6),
                         [](const ::testing::TestParamInfo<int>& param) {
                           return test::closed_object_test_name(param.param);
                         });

TEST(ScannedObjects, OutlierRemovalSameMeshWithOneAndTwoThreads) {
  const synthetic::ClosedObject object = synthetic::box_with_hole_object();
  const synthetic::ObjectScan scan = scanned(object, 32);
  const auto mesh = [&](int threads) {
    return test::with_threads(threads, [&] {
      const FramePtr f = ReconstructionPipeline(scan_config(object)).reconstruct(scan.cloud);
      EXPECT_TRUE(f->ok()) << f->error;
      return std::make_pair(f->filter_counts.isolated, f->mesh);
    });
  };
  const auto one = mesh(1), two = mesh(2);
  EXPECT_GT(one.first, 0u);
  EXPECT_EQ(one.first, two.first);
  EXPECT_EQ(one.second.vertices, two.second.vertices);
  EXPECT_EQ(one.second.triangles, two.second.triangles);
}

}  // namespace
}  // namespace meshflow
