#include "nodes/io/scan3d_reader.h"

#include <gtest/gtest.h>

#include "runtime/error.h"
#include "test_support.h"

namespace meshflow::io {
namespace {

TEST(Scan3dReader, MapsCentimetresLeftHandedToMetresRightHanded) {
  const std::string dir = test::temp_dir();
  // 3DTK frame: x right, y up, z forward (cm). One point 200 cm ahead, 100 cm right, 50 up.
  test::write_file(dir + "/scan000.3d", "360 x 225\n100 50 200\n10 0 10\n0 0 4000\n");
  const PointCloud c = read_3dtk_scan(dir + "/scan000.3d");
  ASSERT_EQ(c.size(), 1u) << "the 14 cm and 40 m points are outside the valid range";
  EXPECT_TRUE(c.positions[0].isApprox(Eigen::Vector3f(2.0f, -1.0f, 0.5f)));
  EXPECT_TRUE(c.has_sensor_origin);
}

TEST(Scan3dReader, AppliesThePose) {
  const std::string dir = test::temp_dir();
  test::write_file(dir + "/scan001.3d", "0 0 100\n");
  // Translation 100 cm along 3DTK z (= meshflow x); rotation 90 degrees about 3DTK y (up).
  test::write_file(dir + "/scan001.pose", "0 0 100\n0 90 0\n\n");
  const PointCloud c = read_3dtk_scan(dir + "/scan001.3d");
  ASSERT_EQ(c.size(), 1u);
  EXPECT_TRUE(c.sensor_origin.isApprox(Eigen::Vector3f(1, 0, 0)));
  // Ry(90) maps 3DTK z to 3DTK x (right), which is meshflow -y.
  EXPECT_TRUE(c.positions[0].isApprox(Eigen::Vector3f(1, -1, 0), 1e-5f))
      << c.positions[0].transpose();
}

TEST(Scan3dReader, TruncatedLineIsAnError) {
  try {
    read_3dtk_scan(test::fixture("bad/truncated.3d"));
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("line 3"), std::string::npos) << e.what();
  }
}

TEST(Scan3dReader, NonFiniteOrHugePoseIsAnError) {
  const std::string dir = test::temp_dir();
  test::write_file(dir + "/s.3d", "1 2 3\n");
  for (const char* pose : {"1e308 0 0\n0 0 0\n", "0 nan 0\n0 0 0\n", "0 0 0\n0 inf 0\n"}) {
    test::write_file(dir + "/s.pose", pose);
    try {
      read_3dtk_scan(dir + "/s.3d");
      ADD_FAILURE() << "no error for the pose " << pose;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("s.pose: line"), std::string::npos) << e.what();
    }
  }
}

TEST(Scan3dReader, RealKurt3dScansAndPoses) {
  MESHFLOW_REQUIRE_DATA("kurt3d/scan000.3d");
  const PointCloud s0 = read_3dtk_scan(test::data_path("kurt3d/scan000.3d"));
  // 81 360 returns less ~2.2k too close and ~1.3-1.6k at maximum range.
  EXPECT_GT(s0.size(), 76000u);
  EXPECT_LT(s0.size(), 79000u);
  EXPECT_TRUE(s0.sensor_origin.isZero());
  const PointCloud s1 = read_3dtk_scan(test::data_path("kurt3d/scan001.3d"));
  EXPECT_TRUE(s1.sensor_origin.isApprox(Eigen::Vector3f(1.5692f, 0.0311f, -0.0751f), 1e-4f))
      << s1.sensor_origin.transpose();
}

}  // namespace
}  // namespace meshflow::io
