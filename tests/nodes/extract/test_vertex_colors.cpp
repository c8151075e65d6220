#include "nodes/extract/vertex_colors.h"

#include <gtest/gtest.h>

#include "graph/pipeline.h"
#include "nodes/synthetic/closed_objects.h"

namespace meshflow {
namespace {

TEST(VertexColors, NearestPointsColourTheVertices) {
  // A plane, red for x < 0.5 and blue beyond; vertices away from the border take their side's
  // colour exactly, one on a point takes that point's.
  PointCloud c;
  for (int i = 0; i <= 100; ++i)
    for (int j = 0; j <= 50; ++j) {
      const float x = 0.01f * static_cast<float>(i);
      c.positions.emplace_back(x, 0.01f * static_cast<float>(j), 0.0f);
      c.colors.push_back(x < 0.5f ? Rgb8{255, 0, 0} : Rgb8{0, 0, 255});
    }
  const KdTreeIndex index(c.positions);
  const std::vector<Eigen::Vector3f> vertices = {
      {0.2f, 0.2f, 0.03f}, {0.8f, 0.3f, -0.02f}, {0.3f, 0.25f, 0.0f}};
  const std::vector<Rgb8> colors = vertex_colors(vertices, c, index);
  EXPECT_EQ(colors[0], (Rgb8{255, 0, 0}));
  EXPECT_EQ(colors[1], (Rgb8{0, 0, 255}));
  EXPECT_EQ(colors[2], (Rgb8{255, 0, 0}));
}

TEST(VertexColors, AColouredCloudGivesAColouredMesh) {
  // The torus painted by height: the mesh's vertices carry the colour of the points near them.
  PointCloud c = synthetic::torus_object().sample(30000, 0.0f, 2);
  c.normals.clear();
  for (const Eigen::Vector3f& p : c.positions)
    c.colors.push_back(p.z() > 0.0f ? Rgb8{200, 30, 30} : Rgb8{30, 30, 200});
  ReconstructionConfig config;
  config.voxelize.voxel_size = 0.02f;
  const FramePtr f = ReconstructionPipeline(config).reconstruct(c);
  ASSERT_TRUE(f->ok()) << f->error;
  ASSERT_EQ(f->mesh.colors.size(), f->mesh.vertices.size());
  std::size_t right = 0, far_from_the_middle = 0;
  for (std::size_t v = 0; v < f->mesh.vertices.size(); ++v) {
    const float z = f->mesh.vertices[v].z();
    if (std::abs(z) < 0.03f) continue;
    ++far_from_the_middle;
    right += f->mesh.colors[v] == (z > 0.0f ? Rgb8{200, 30, 30} : Rgb8{30, 30, 200}) ? 1 : 0;
  }
  EXPECT_EQ(right, far_from_the_middle);
}

}  // namespace
}  // namespace meshflow
