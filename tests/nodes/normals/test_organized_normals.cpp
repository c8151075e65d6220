#include "nodes/normals/organized_normals.h"

#include <gtest/gtest.h>

#include <random>

#include "nodes/synthetic/depth_sequence.h"

namespace meshflow {
namespace {

TEST(OrganizedNormals, FrontoParallelPlaneInTheWorldFrame) {
  DepthFrame f;
  f.intrinsics = PinholeIntrinsics{40, 30, 50.0f, 50.0f, 19.5f, 14.5f};
  f.depth = Image::filled<float>(30, 40, 2.0f);
  f.depth.at<float>(3, 3) = 0.0f;
  f.T_world_camera = synthetic::look_at({1, 2, 3}, {1, 2, 0});  // looking straight down
  const PointCloud c = back_project(f, f.depth);
  EXPECT_TRUE(c.is_organized());
  EXPECT_TRUE(c.sensor_origin.isApprox(Eigen::Vector3f(1, 2, 3)));
  std::size_t valid = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (!c.positions[i].allFinite()) continue;
    ++valid;
    EXPECT_NEAR(c.positions[i].z(), 1.0f, 1e-5f);  // 2 m below the camera
    EXPECT_TRUE(c.normals[i].isApprox(Eigen::Vector3f(0, 0, 1), 1e-4f)) << c.normals[i].transpose();
  }
  EXPECT_EQ(valid, 40u * 30u - 1u);
  // Pixel (u, v) = (39, 14): x_cam = (39 - 19.5) * 2 / 50 = 0.78 m to the right.
  const Eigen::Vector3f p = c.positions[14 * 40 + 39];
  EXPECT_NEAR((p - Eigen::Vector3f(1, 2, 1)).norm(), std::hypot(0.78f, 0.5f * 2.0f / 50.0f), 1e-4f);
}

TEST(OrganizedNormals, ValidOnlyBackProjectionKeepsTheFinitePixelsInOrder) {
  const synthetic::Scene scene = synthetic::demo_room_scene();
  const Eigen::Vector3f eye = scene.room.center;
  PinholeIntrinsics k{64, 48, 52.5f, 52.5f, 31.5f, 23.5f};
  DepthFrame f = synthetic::render_depth(
      scene, k, synthetic::look_at(eye, eye + Eigen::Vector3f(1, 0.3f, -0.35f)), 0.0f);
  Image depth = depth_in_metres(f);
  depth.at<float>(10, 10) = 0.0f;  // holes: isolated pixels lose their normals too
  depth.at<float>(11, 12) = 0.0f;
  f.color = Image(48, 64, PixelFormat::RGB8);
  std::mt19937 rng(3);
  for (int v = 0; v < f.color.rows(); ++v)
    for (int u = 0; u < f.color.cols(); ++u) {
      const std::uint32_t bits = rng();
      f.color.at<Rgb8>(v, u) =
          Rgb8{static_cast<std::uint8_t>(bits), static_cast<std::uint8_t>(bits >> 8),
               static_cast<std::uint8_t>(bits >> 16)};
    }
  const PointCloud organized = back_project(f, depth);
  const PointCloud valid = back_project_valid(f, depth);
  EXPECT_FALSE(valid.is_organized());
  EXPECT_TRUE(valid.has_sensor_origin);
  ASSERT_EQ(valid.colors.size(), valid.size());
  std::size_t j = 0;
  for (std::size_t i = 0; i < organized.size(); ++i) {
    if (!organized.positions[i].allFinite()) continue;
    ASSERT_LT(j, valid.size());
    EXPECT_EQ(valid.positions[j], organized.positions[i]);
    EXPECT_EQ(valid.normals[j], organized.normals[i]);
    EXPECT_EQ(valid.colors[j].r, organized.colors[i].r);
    ++j;
  }
  EXPECT_EQ(j, valid.size());
  EXPECT_GT(j, 64u * 48u * 9u / 10u);
  EXPECT_LE(j, 64u * 48u - 2u);
}

}  // namespace
}  // namespace meshflow
