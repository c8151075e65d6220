#include "nodes/io/sequence.h"

#include <gtest/gtest.h>

#include "runtime/error.h"
#include "test_support.h"

namespace meshflow::io {
namespace {

TEST(Sequence, ThreeDtkDirectoryInNumericOrderWithPoses) {
  const std::string dir = test::temp_dir();
  test::write_file(dir + "/scan2.3d", "0 0 100\n");
  test::write_file(dir + "/scan2.pose", "0 0 0\n0 0 0\n");
  test::write_file(dir + "/scan10.3d", "0 0 200\n");
  test::write_file(dir + "/scan10.pose", "0 0 50\n0 0 0\n");
  test::write_file(dir + "/scan11.3d", "0 0 300\n");  // no pose
  test::write_file(dir + "/notes.txt", "ignored\n");
  const auto seq = open_sequence(dir);
  ASSERT_EQ(seq->size(), 3u);
  EXPECT_NE(seq->description().find("3 frames"), std::string::npos);
  EXPECT_NE(seq->frame(0).name.find("scan2.3d"), std::string::npos);
  EXPECT_NE(seq->frame(1).name.find("scan10.3d"), std::string::npos);
  const PointCloud second = seq->frame(1).load();
  ASSERT_EQ(second.size(), 1u);
  EXPECT_TRUE(second.positions[0].isApprox(Eigen::Vector3f(2.5f, 0, 0)));
  EXPECT_TRUE(second.sensor_origin.isApprox(Eigen::Vector3f(0.5f, 0, 0)));
  try {
    seq->frame(2).load();
    FAIL() << "a scan without its pose must not load";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("scan11.pose"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("pose file missing"), std::string::npos) << e.what();
  }
}

TEST(Sequence, SingleFileAndErrors) {
  const std::string dir = test::temp_dir();
  test::write_file(dir + "/c.xyz", "1 2 3\n");
  const auto single = open_sequence(dir + "/c.xyz");
  ASSERT_EQ(single->size(), 1u);
  EXPECT_EQ(single->frame(0).load().size(), 1u);
  EXPECT_THROW(open_sequence(dir + "/missing"), Error);
  EXPECT_THROW(open_sequence(test::temp_dir()), Error);  // empty directory: no scans
}

TEST(Sequence, RealKurt3dDirectory) {
  MESHFLOW_REQUIRE_DATA("kurt3d/scan000.3d");
  const auto seq = open_sequence(test::data_path("kurt3d"));
  ASSERT_EQ(seq->size(), 3u);
  EXPECT_TRUE(seq->frame(2).load().sensor_origin.isApprox(Eigen::Vector3f(3.3797f, 0.08f, -0.1535f),
                                                          1e-3f));
}

}  // namespace
}  // namespace meshflow::io
