#include "nodes/depth/organized_depth.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "nodes/normals/organized_normals.h"
#include "nodes/synthetic/depth_sequence.h"
#include "test_support.h"

namespace meshflow {
namespace {

// A ray-cast frame of the demo room (160 x 120, off-centre principal point) and its organized
// cloud in the camera frame, as a Kinect driver would produce it.
struct OrganizedFrame {
  DepthFrame depth;
  PointCloud cloud;
};

OrganizedFrame organized_room_frame() {
  synthetic::DepthSequenceConfig c;
  c.frames = 1;
  c.intrinsics = PinholeIntrinsics{160, 120, 131.25f, 128.5f, 77.25f, 61.5f};
  OrganizedFrame f;
  f.depth = synthetic::make_depth_sequence(synthetic::demo_room_scene(), c)->frame(0).load_depth();
  f.cloud = test::camera_frame_cloud(f.depth);
  return f;
}

TEST(OrganizedDepth, RecoversTheIntrinsicsAndTheDepthOfAPinholeCloud) {
  const OrganizedFrame f = organized_room_frame();
  ASSERT_TRUE(f.cloud.is_organized());
  const std::optional<DepthFrame> d = depth_frame_from_organized(f.cloud);
  ASSERT_TRUE(d.has_value());
  const PinholeIntrinsics& k = d->intrinsics;
  EXPECT_EQ(k.width, 160);
  EXPECT_EQ(k.height, 120);
  EXPECT_NEAR(k.fx, 131.25f, 1e-2f);
  EXPECT_NEAR(k.fy, 128.5f, 1e-2f);
  EXPECT_NEAR(k.cx, 77.25f, 1e-2f);
  EXPECT_NEAR(k.cy, 61.5f, 1e-2f);
  EXPECT_TRUE(d->T_world_camera.isApprox(Eigen::Isometry3f::Identity()));
  ASSERT_EQ(d->depth.format(), PixelFormat::F32);
  const Image truth = depth_in_metres(f.depth);
  std::size_t valid = 0;
  for (int v = 0; v < 120; ++v)
    for (int u = 0; u < 160; ++u) {
      const Eigen::Vector3f& p = f.cloud.positions[static_cast<std::size_t>(v * 160 + u)];
      if (!p.allFinite()) {
        EXPECT_EQ(d->depth.at<float>(v, u), 0.0f);
        continue;
      }
      ++valid;
      EXPECT_NEAR(d->depth.at<float>(v, u), truth.at<float>(v, u), 1e-5f);
    }
  EXPECT_GT(valid, 15000u);
}

TEST(OrganizedDepth, KeepsColoursAndTheSensorOrigin) {
  OrganizedFrame f = organized_room_frame();
  const Eigen::Vector3f origin(1.0f, -2.0f, 0.5f);
  for (auto& p : f.cloud.positions) p += origin;
  f.cloud.sensor_origin = origin;
  f.cloud.has_sensor_origin = true;
  f.cloud.colors.assign(f.cloud.size(), Rgb8{10, 20, 30});
  f.cloud.colors[160 * 60 + 80] = Rgb8{200, 100, 50};
  const std::optional<DepthFrame> d = depth_frame_from_organized(f.cloud);
  ASSERT_TRUE(d.has_value());
  EXPECT_TRUE(d->T_world_camera.translation().isApprox(origin));
  ASSERT_EQ(d->color.format(), PixelFormat::RGB8);
  EXPECT_EQ(d->color.at<Rgb8>(60, 80), (Rgb8{200, 100, 50}));
  EXPECT_EQ(d->color.at<Rgb8>(0, 0), (Rgb8{10, 20, 30}));
  // Back-projecting the recovered frame gives the cloud's points (world frame) again.
  const PointCloud again = back_project(*d, depth_in_metres(*d));
  std::size_t compared = 0;
  for (std::size_t i = 0; i < again.size(); ++i) {
    if (!again.positions[i].allFinite() || !f.cloud.positions[i].allFinite()) continue;
    EXPECT_LT((again.positions[i] - f.cloud.positions[i]).norm(), 1e-4f) << i;
    ++compared;
  }
  EXPECT_GT(compared, 15000u);
}

TEST(OrganizedDepth, RefusesCloudsThatAreNotAPinholeView) {
  const OrganizedFrame f = organized_room_frame();
  PointCloud unorganized = f.cloud;
  unorganized.height = 1;
  unorganized.width = static_cast<std::uint32_t>(unorganized.size());
  EXPECT_FALSE(depth_frame_from_organized(unorganized).has_value());

  PointCloud turned = f.cloud;  // moved into a world frame: a 10 degree turn about y
  const Eigen::Matrix3f r = Eigen::AngleAxisf(0.1745f, Eigen::Vector3f::UnitY()).toRotationMatrix();
  for (auto& p : turned.positions) p = r * p;
  EXPECT_FALSE(depth_frame_from_organized(turned).has_value());

  PointCloud jittered = f.cloud;  // half a pixel of lateral error on one point
  for (auto& p : jittered.positions)
    if (p.allFinite()) {
      p.x() += 0.5f * p.z() / 131.25f;
      break;
    }
  EXPECT_FALSE(depth_frame_from_organized(jittered).has_value());
  EXPECT_TRUE(depth_frame_from_organized(jittered, 1.0).has_value()) << "within a 1 px tolerance";

  PointCloud behind = f.cloud;
  for (auto& p : behind.positions)
    if (p.allFinite()) {
      p = -p;
      break;
    }
  EXPECT_FALSE(depth_frame_from_organized(behind).has_value());

  PointCloud sparse = f.cloud;  // 15 valid points are too few to fit
  std::size_t kept = 0;
  for (auto& p : sparse.positions)
    if (p.allFinite() && ++kept > 15) p = Eigen::Vector3f::Constant(NAN);
  EXPECT_FALSE(depth_frame_from_organized(sparse).has_value());
}

}  // namespace
}  // namespace meshflow
