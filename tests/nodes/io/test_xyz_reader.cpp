#include "nodes/io/xyz_reader.h"

#include <gtest/gtest.h>

#include "runtime/error.h"
#include "test_support.h"

namespace meshflow::io {
namespace {

TEST(XyzReader, ColumnLayouts) {
  const std::string dir = test::temp_dir();
  test::write_file(dir + "/3.xyz", "# comment\n1 2 3\n4 5 6\n");
  test::write_file(dir + "/4.xyz", "1 2 3 0.5\n");
  test::write_file(dir + "/6.xyz", "1 2 3 10 20 30\n");
  test::write_file(dir + "/7.pts", "2\n1 2 3 0.5 10 20 30\n4 5 6 0.25 1 2 3\n");
  EXPECT_EQ(read_xyz(dir + "/3.xyz").size(), 2u);
  const PointCloud c4 = read_xyz(dir + "/4.xyz");
  EXPECT_EQ(c4.intensities[0], 0.5f);
  EXPECT_FALSE(c4.has_colors());
  const PointCloud c6 = read_xyz(dir + "/6.xyz");
  EXPECT_EQ(c6.colors[0], (Rgb8{10, 20, 30}));
  EXPECT_FALSE(c6.has_intensities());
  const PointCloud c7 = read_xyz(dir + "/7.pts");
  ASSERT_EQ(c7.size(), 2u);
  EXPECT_EQ(c7.intensities[1], 0.25f);
  EXPECT_EQ(c7.colors[1], (Rgb8{1, 2, 3}));
}

TEST(XyzReader, ErrorsNameFileAndLine) {
  const std::string dir = test::temp_dir();
  test::write_file(dir + "/count.pts", "5\n1 2 3\n");
  EXPECT_THROW(read_xyz(dir + "/count.pts"), Error);
  try {
    read_xyz(test::fixture("bad/bad_columns.xyz"));
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("line 2"), std::string::npos) << e.what();
  }
  try {
    read_xyz(test::fixture("bad/overflow.xyz"));
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("out of the range"), std::string::npos) << e.what();
  }
}

TEST(XyzReader, NaNRowsAreKeptForTheFilterToCount) {
  const PointCloud c = read_xyz(test::fixture("bad/nan_rows.xyz"));
  EXPECT_EQ(c.size(), 4u);
  for (const auto& p : c.positions) EXPECT_FALSE(p.allFinite());
}

}  // namespace
}  // namespace meshflow::io
