#include "nodes/io/rgbd_sequences.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "runtime/error.h"
#include "test_support.h"

namespace meshflow::io {
namespace {

void write_depth_png(const std::string& path, std::uint16_t value, int w = 8, int h = 6) {
  ASSERT_TRUE(cv::imwrite(path, cv::Mat(h, w, CV_16U, cv::Scalar(value))));
}

const char* kCameraJson =
    R"({"width": 8, "height": 6, "intrinsic_matrix": [10, 0, 0, 0, 11, 0, 3.5, 2.5, 1]})";

TEST(RgbdSequences, RedwoodLayoutWithTrajectoryAndIntrinsics) {
  const std::string dir = test::temp_dir();
  std::filesystem::create_directories(dir + "/depth");
  write_depth_png(dir + "/depth/00000.png", 1000);
  write_depth_png(dir + "/depth/00001.png", 2000);
  write_depth_png(dir + "/depth/00002.png", 3000);
  test::write_file(dir + "/camera.json", kCameraJson);
  test::write_file(dir + "/trajectory.log",
                   "0 0 1\n1 0 0 0.5\n0 1 0 0\n0 0 1 0\n0 0 0 1\n"
                   "1 1 2\n1\t0\t0\t1.5\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");  // two poses, three images
  const auto seq = open_sequence(dir);
  ASSERT_EQ(seq->size(), 3u);
  const DepthFrame f1 = seq->frame(1).load_depth();
  EXPECT_EQ(f1.intrinsics.fx, 10.0f);
  EXPECT_EQ(f1.intrinsics.fy, 11.0f);
  EXPECT_EQ(f1.intrinsics.cx, 3.5f);
  EXPECT_EQ(f1.depth.at<std::uint16_t>(0, 0), 2000);
  EXPECT_TRUE(f1.T_world_camera.translation().isApprox(Eigen::Vector3f(1.5f, 0, 0)));
  try {
    seq->frame(2).load_depth();
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("pose missing for frame 2"), std::string::npos)
        << e.what();
  }
  test::write_file(dir + "/depth/00000.png", "not a png");
  EXPECT_THROW(seq->frame(0).load_depth(), Error);
}

TEST(RgbdSequences, TumLayoutAssociatesByTimestamp) {
  const std::string dir = test::temp_dir();
  std::filesystem::create_directories(dir + "/depth");
  write_depth_png(dir + "/depth/1.000000.png", 5000);   // 1 m at TUM's scale 5000
  write_depth_png(dir + "/depth/1.033333.png", 10000);  // 2 m
  write_depth_png(dir + "/depth/1.500000.png", 5000);
  test::write_file(dir + "/camera.json", kCameraJson);
  test::write_file(
      dir + "/depth.txt",
      "# depth maps\n# file: 'fixture'\n# timestamp filename\n"
      "1.000000 depth/1.000000.png\n1.033333 depth/1.033333.png\n1.500000 depth/1.500000.png\n");
  test::write_file(dir + "/groundtruth.txt",
                   "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n"
                   "0.995 0 0 0 0 0 0 1\n1.040 1 2 3 0 0 0.7071068 0.7071068\n");
  const auto seq = open_sequence(dir);
  ASSERT_EQ(seq->size(), 3u);
  const DepthFrame f0 = seq->frame(0).load_depth();
  EXPECT_TRUE(f0.T_world_camera.translation().isZero());
  EXPECT_NEAR(depth_in_metres(f0).at<float>(0, 0), 1.0f, 1e-6f);
  const DepthFrame f1 = seq->frame(1).load_depth();  // nearest pose: 1.040 (6.7 ms away)
  EXPECT_TRUE(f1.T_world_camera.translation().isApprox(Eigen::Vector3f(1, 2, 3)));
  EXPECT_TRUE((f1.T_world_camera.linear() * Eigen::Vector3f::UnitX())
                  .isApprox(Eigen::Vector3f::UnitY(), 1e-5f));
  EXPECT_NEAR(depth_in_metres(f1).at<float>(0, 0), 2.0f, 1e-6f);
  try {
    seq->frame(2).load_depth();  // no pose within 20 ms of 1.5 s
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("depth.txt: timestamp 1.500000"), std::string::npos)
        << e.what();
  }
}

TEST(RgbdSequences, MalformedTrajectoryAndIntrinsics) {
  const std::string dir = test::temp_dir();
  test::write_file(dir + "/t.log", "0 0 1\n1 0 0\n");
  EXPECT_THROW(read_trajectory_log(dir + "/t.log"), Error);
  test::write_file(dir + "/s.log",
                   "0 0 1\n2 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");  // scaled: not rigid
  EXPECT_THROW(read_trajectory_log(dir + "/s.log"), Error);
  test::write_file(dir + "/c.json", R"({"width": 8, "intrinsic_matrix": [1, 2]})");
  EXPECT_THROW(read_intrinsics_json(dir + "/c.json"), Error);
  test::write_file(dir + "/d.json", "{not json");
  EXPECT_THROW(read_intrinsics_json(dir + "/d.json"), Error);
}

TEST(RgbdSequences, DepthImageDirectoryWithoutPoses) {
  const std::string dir = test::temp_dir();
  write_depth_png(dir + "/a_depth.png", 1200);
  write_depth_png(dir + "/b_depth.png", 1300);
  ASSERT_TRUE(
      cv::imwrite(dir + "/a_rgb.png", cv::Mat(6, 8, CV_8UC3, cv::Scalar(255, 0, 0))));  // BGR blue
  ASSERT_TRUE(
      cv::imwrite(dir + "/b_rgb.png", cv::Mat(6, 8, CV_8UC3, cv::Scalar(0, 0, 255))));  // BGR red
  test::write_file(dir + "/camera.json", kCameraJson);
  const auto seq = open_sequence(dir);
  ASSERT_EQ(seq->size(), 2u);
  EXPECT_NE(seq->description().find("no poses"), std::string::npos);
  const DepthFrame f = seq->frame(1).load_depth();
  EXPECT_EQ(f.depth.at<std::uint16_t>(2, 2), 1300);
  EXPECT_TRUE(f.T_world_camera.matrix().isIdentity());
  EXPECT_EQ(f.color.at<cv::Vec3b>(0, 0), cv::Vec3b(255, 0, 0)) << "colour is stored RGB";
}

TEST(RgbdSequences, RealKinectGrabberFrames) {
  MESHFLOW_REQUIRE_DATA("kinect_pcl/grabber_sequences/tiff");
  const auto tiff = open_sequence(test::data_path("kinect_pcl/grabber_sequences/tiff"));
  ASSERT_EQ(tiff->size(), 3u);
  const DepthFrame f = tiff->frame(0).load_depth();
  EXPECT_EQ(f.depth.cols, 640);
  const int invalid = static_cast<int>(f.depth.total()) - cv::countNonZero(f.depth);
  EXPECT_GT(invalid, 35000);  // 35.6k-35.9k pixels without depth
  EXPECT_LT(invalid, 36500);
  const auto pcd = open_sequence(test::data_path("kinect_pcl/grabber_sequences/pcd"));
  ASSERT_EQ(pcd->size(), 3u);
  const PointCloud c = pcd->frame(0).load();
  EXPECT_TRUE(c.is_organized());
  const std::size_t finite = count_finite_points(c);
  EXPECT_EQ(finite, 271575u);
}

TEST(RgbdSequences, RealRedwoodFrames) {
  MESHFLOW_REQUIRE_DATA("rgbd_redwood/trajectory.log");
  const auto seq = open_sequence(test::data_path("rgbd_redwood"));
  ASSERT_EQ(seq->size(), 5u);
  const DepthFrame f = seq->frame(0).load_depth();
  EXPECT_EQ(f.depth.cols, 640);
  EXPECT_EQ(f.intrinsics.fx, 525.0f);
  EXPECT_EQ(f.intrinsics.cx, 319.5f);
  EXPECT_TRUE(
      f.T_world_camera.translation().isApprox(Eigen::Vector3f(-0.311f, 0.573f, 2.126f), 2e-3f))
      << f.T_world_camera.translation().transpose();
  EXPECT_EQ(f.color.type(), CV_8UC3);
  const double valid = cv::countNonZero(f.depth) / static_cast<double>(f.depth.total());
  EXPECT_GT(valid, 0.8);  // 12-13 % of pixels have no depth
}

}  // namespace
}  // namespace meshflow::io
