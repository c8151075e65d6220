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

TEST(VertexColors, VerticesTakeTheColourOfTheirPixel) {
  // A camera at (0, 0, -1) looking along +z; red grows with u, green with v.
  DepthFrame frame;
  frame.intrinsics = PinholeIntrinsics{64, 48, 50.0f, 50.0f, 32.0f, 24.0f};
  frame.depth = Image::filled<std::uint16_t>(48, 64, 1000);
  frame.color = Image(48, 64, PixelFormat::RGB8);
  for (int v = 0; v < 48; ++v)
    for (int u = 0; u < 64; ++u)
      frame.color.at<Rgb8>(v, u) =
          Rgb8{static_cast<std::uint8_t>(3 * u), static_cast<std::uint8_t>(5 * v), 7};
  frame.T_world_camera.translation() = Eigen::Vector3f(0, 0, -1);
  // Pixel (10, 20) at depth 2 (world z = 1); a point between pixels; one far outside the image.
  const Eigen::Vector3f at_pixel((10 - 32) * 2.0f / 50, (20 - 24) * 2.0f / 50, 1.0f);
  const Eigen::Vector3f between((10.5f - 32) * 1.0f / 50, (20 - 24) * 1.0f / 50, 0.0f);
  const std::vector<Rgb8> c =
      vertex_colors_from_image({at_pixel, between, {100.0f, 0.0f, 1.0f}}, frame);
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c[0], (Rgb8{30, 100, 7}));
  EXPECT_EQ(c[1].r, 32);      // halfway between 30 and 33, rounded
  EXPECT_EQ(c[2].r, 3 * 63);  // clamped to the border column
  frame.color = Image();
  EXPECT_TRUE(vertex_colors_from_image({at_pixel}, frame).empty());
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
