#include "nodes/normals/organized_normals.h"

#include <gtest/gtest.h>

#include "nodes/synthetic/depth_sequence.h"

namespace meshflow {
namespace {

TEST(OrganizedNormals, FrontoParallelPlaneInTheWorldFrame) {
  DepthFrame f;
  f.intrinsics = PinholeIntrinsics{40, 30, 50.0f, 50.0f, 19.5f, 14.5f};
  f.depth = cv::Mat(30, 40, CV_32F, cv::Scalar(2.0f));
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

}  // namespace
}  // namespace meshflow
