#include "nodes/io/rgbd_sequences.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "nodes/io/image_io.h"
#include "runtime/error.h"
#include "test_support.h"

namespace meshflow::io {
namespace {

void write_depth_png(const std::string& path, std::uint16_t value, int w = 8, int h = 6) {
  write_png(path, Image::filled<std::uint16_t>(h, w, value));
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

// The message of the meshflow::Error that f() throws (a test failure when it throws none).
template <typename F>
std::string error_of(F f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no meshflow::Error";
  return "";
}

// Values that parse as numbers but would make every point garbage (a NaN or infinite pose, a
// focal length or image size beyond float or int) are errors naming the file, line or field.
TEST(RgbdSequences, NonFiniteOrHugePosesAndIntrinsicsAreErrors) {
  const std::string dir = test::temp_dir();
  test::write_file(dir + "/t.log", "0 0 1\n1 0 0 0\n0 1 0 1e39\n0 0 1 0\n0 0 0 1\n");
  std::string e = error_of([&] { read_trajectory_log(dir + "/t.log"); });
  EXPECT_NE(e.find("t.log: line 5"), std::string::npos) << e;
  EXPECT_NE(e.find("translation"), std::string::npos) << e;
  for (const char* json :
       {R"({"width": 1e20, "height": 6, "intrinsic_matrix": [10, 0, 0, 0, 11, 0, 3, 2, 1]})",
        R"({"width": 8.5, "height": 6, "intrinsic_matrix": [10, 0, 0, 0, 11, 0, 3, 2, 1]})",
        R"({"width": 8, "height": 6, "intrinsic_matrix": [1e308, 0, 0, 0, 11, 0, 3, 2, 1]})",
        R"({"width": 8, "height": 6, "intrinsic_matrix": [10, 0, 0, 0, "11", 0, 3, 2, 1]})",
        R"({"width": 8, "height": 6, "intrinsic_matrix": [10, 0, 0, 0, 11, 0, 3, -1e39, 1]})"}) {
    test::write_file(dir + "/c.json", json);
    e = error_of([&] { read_intrinsics_json(dir + "/c.json"); });
    EXPECT_NE(e.find("c.json"), std::string::npos) << e;
    const bool names_field = e.find("width") != std::string::npos ||
                             e.find("fx") != std::string::npos ||
                             e.find("fy") != std::string::npos || e.find("cy") != std::string::npos;
    EXPECT_TRUE(names_field) << e;
  }
  test::write_file(dir + "/depth.txt", "inf depth/a.png\n");
  test::write_file(dir + "/groundtruth.txt", "1 0 0 0 0 0 0 1\n");
  e = error_of([&] { open_tum_directory(dir); });
  EXPECT_NE(e.find("depth.txt: line 1"), std::string::npos) << e;
  test::write_file(dir + "/depth.txt", "1 depth/a.png\n");
  test::write_file(dir + "/groundtruth.txt", "# t tx ty tz qx qy qz qw\n1 0 nan 0 0 0 0 1\n");
  e = error_of([&] { open_tum_directory(dir); });
  EXPECT_NE(e.find("groundtruth.txt: line 2"), std::string::npos) << e;
  test::write_file(dir + "/groundtruth.txt", "1 0 2e6 0 0 0 0 1\n");
  e = error_of([&] { open_tum_directory(dir); });
  EXPECT_NE(e.find("translation"), std::string::npos) << e;
}

// Fuzz-style corruption of the sequence files (truncations and byte flips of a trajectory, a
// camera JSON, TUM lists): each either reads to finite values or throws meshflow::Error.
TEST(RgbdSequences, CorruptedSequenceFilesNeverCrashOrGiveNonFiniteValues) {
  const std::string dir = test::temp_dir();
  const std::string log =
      "0 0 1\n1 0 0 0.5\n0 1 0 -2\n0 0 1 3\n0 0 0 1\n"
      "1 1 2\n0 -1 0 0\n1 0 0 1e2\n0 0 1 0\n0 0 0 1\n";
  const std::string json =
      R"({"width": 640, "height": 480, "intrinsic_matrix": [525, 0, 0, 0, 525, 0, 319.5, 239.5, 1]})";
  const std::string depth_list = "# depth\n1.160407 depth/1.160407.png\n1.194330 depth/1.19.png\n";
  const std::string groundtruth =
      "# gt\n1.15 1.3 0.6 1.6 0.65 0.62 -0.29 -0.32\n1.19 1.3 0.6 1.6 0.65 0.62 -0.29 -0.32\n";
  std::uint32_t state = 2024;
  const auto corruptions = [&](const std::string& good) {
    std::vector<std::string> out;
    for (std::size_t len = 0; len < good.size(); ++len) out.push_back(good.substr(0, len));
    for (int trial = 0; trial < 300; ++trial) out.push_back(test::flip_bytes(good, 2, state));
    return out;
  };
  for (const std::string& text : corruptions(log)) {
    test::write_file(dir + "/t.log", text);
    try {
      for (const Eigen::Isometry3f& pose : read_trajectory_log(dir + "/t.log"))
        EXPECT_TRUE(pose.matrix().allFinite()) << text;
    } catch (const Error&) {
    }
  }
  for (const std::string& text : corruptions(json)) {
    test::write_file(dir + "/c.json", text);
    try {
      const PinholeIntrinsics k = read_intrinsics_json(dir + "/c.json");
      EXPECT_TRUE(k.width > 0 && k.height > 0 && k.fx > 0.0f && k.fy > 0.0f) << text;
      EXPECT_TRUE(std::isfinite(k.fx) && std::isfinite(k.fy) && std::isfinite(k.cx) &&
                  std::isfinite(k.cy))
          << text;
    } catch (const Error&) {
    }
  }
  for (int which = 0; which < 2; ++which)
    for (const std::string& text : corruptions(which == 0 ? depth_list : groundtruth)) {
      test::write_file(dir + "/depth.txt", which == 0 ? text : depth_list);
      test::write_file(dir + "/groundtruth.txt", which == 1 ? text : groundtruth);
      try {
        const auto seq = open_tum_directory(dir);
        for (std::size_t i = 0; i < seq->size(); ++i)
          EXPECT_TRUE(std::isfinite(seq->frame(i).timestamp_s)) << text;
      } catch (const Error&) {
      }
    }
}

TEST(RgbdSequences, DepthImageDirectoryWithoutPoses) {
  const std::string dir = test::temp_dir();
  write_depth_png(dir + "/a_depth.png", 1200);
  write_depth_png(dir + "/b_depth.png", 1300);
  write_png(dir + "/a_rgb.png", Image::filled<Rgb8>(6, 8, Rgb8{255, 0, 0}));  // RGB red
  write_png(dir + "/b_rgb.png", Image::filled<Rgb8>(6, 8, Rgb8{0, 0, 255}));  // RGB blue
  test::write_file(dir + "/camera.json", kCameraJson);
  const auto seq = open_sequence(dir);
  ASSERT_EQ(seq->size(), 2u);
  EXPECT_NE(seq->description().find("no poses"), std::string::npos);
  const DepthFrame f = seq->frame(1).load_depth();
  EXPECT_EQ(f.depth.at<std::uint16_t>(2, 2), 1300);
  EXPECT_TRUE(f.T_world_camera.matrix().isIdentity());
  EXPECT_EQ(f.color.at<Rgb8>(0, 0), (Rgb8{0, 0, 255})) << "colour is stored RGB";
}

TEST(RgbdSequences, RealKinectGrabberFrames) {
  MESHFLOW_REQUIRE_DATA("kinect_pcl/grabber_sequences/tiff");
  const auto tiff = open_sequence(test::data_path("kinect_pcl/grabber_sequences/tiff"));
  ASSERT_EQ(tiff->size(), 3u);
  const DepthFrame f = tiff->frame(0).load_depth();
  EXPECT_EQ(f.depth.cols(), 640);
  const int invalid = static_cast<int>(f.depth.pixels() - count_nonzero(f.depth));
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
  EXPECT_EQ(f.depth.cols(), 640);
  EXPECT_EQ(f.intrinsics.fx, 525.0f);
  EXPECT_EQ(f.intrinsics.cx, 319.5f);
  EXPECT_TRUE(
      f.T_world_camera.translation().isApprox(Eigen::Vector3f(-0.311f, 0.573f, 2.126f), 2e-3f))
      << f.T_world_camera.translation().transpose();
  EXPECT_EQ(f.color.format(), PixelFormat::RGB8);
  const double valid =
      static_cast<double>(count_nonzero(f.depth)) / static_cast<double>(f.depth.pixels());
  EXPECT_GT(valid, 0.8);  // 12-13 % of pixels have no depth
}

}  // namespace
}  // namespace meshflow::io
