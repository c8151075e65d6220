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

TEST(XyzReader, NormalsHeadersAndSeparators) {
  const std::string dir = test::temp_dir();
  // Six columns whose last three are unit vectors: normals, not colours.
  test::write_file(dir + "/n.xyz", "0 0 0 0 0.6 0.8\n1 0 0 -0.6 0 -0.8\n");
  const PointCloud n = read_xyz(dir + "/n.xyz");
  ASSERT_EQ(n.normals.size(), 2u);
  EXPECT_FALSE(n.has_colors());
  EXPECT_EQ(n.normals[1], Eigen::Vector3f(-0.6f, 0.0f, -0.8f));
  // Integers 0 0 1 are a colour.
  test::write_file(dir + "/c.xyz", "0 0 0 0 0 1\n");
  EXPECT_TRUE(read_xyz(dir + "/c.xyz").has_colors());
  // Nine columns in either order.
  test::write_file(dir + "/9.txt", "0 0 0 255 0 10 0 0.6 0.8\n");
  const PointCloud nine = read_xyz(dir + "/9.txt");
  EXPECT_EQ(nine.colors[0], (Rgb8{255, 0, 10}));
  EXPECT_EQ(nine.normals[0], Eigen::Vector3f(0.0f, 0.6f, 0.8f));
  // A CSV with a header line naming the columns in its own order, extra columns skipped.
  test::write_file(
      dir + "/h.csv",
      "label,Z,Y,X,Nx,Ny,Nz,Red,Green,Blue\n7,3,2,1,0,0,1,1,2,3\n8,6,5,4,1,0,0,4,5,6\n");
  const PointCloud h = read_xyz(dir + "/h.csv");
  ASSERT_EQ(h.size(), 2u);
  EXPECT_EQ(h.positions[0], Eigen::Vector3f(1, 2, 3));
  EXPECT_EQ(h.normals[1], Eigen::Vector3f(1, 0, 0));
  EXPECT_EQ(h.colors[1], (Rgb8{4, 5, 6}));
  // CloudCompare's '//X Y Z ...' header.
  test::write_file(dir + "/cc.asc", "//X Y Z Intensity\n1 2 3 0.5\n");
  EXPECT_EQ(read_xyz(dir + "/cc.asc").intensities[0], 0.5f);
  // A header without z, or with half a normal: one clear error.
  test::write_file(dir + "/noz.csv", "x,y,value\n1,2,3\n");
  EXPECT_THROW(read_xyz(dir + "/noz.csv"), Error);
  test::write_file(dir + "/half.csv", "x,y,z,nx\n1,2,3,1\n");
  EXPECT_THROW(read_xyz(dir + "/half.csv"), Error);
}

TEST(XyzReader, ExplicitColumnsReplaceHeaderAndDetection) {
  const std::string dir = test::temp_dir();
  // Six columns that detection would take for colours (integers), and a header it would read.
  test::write_file(dir + "/n.txt", "a b c d e f g\n1 2 3 0 0 1 7\n4 5 6 0 1 0 8\n");
  const PointCloud c = read_xyz(dir + "/n.txt", "x,y,z,nx,ny,nz,intensity");
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.normals[1], Eigen::Vector3f(0, 1, 0));
  EXPECT_EQ(c.intensities[0], 7.0f);
  EXPECT_FALSE(c.has_colors());
  const PointCloud skipped = read_xyz(dir + "/n.txt", "x y z skip _ skip intensity");
  EXPECT_FALSE(skipped.has_normals());
  EXPECT_EQ(read_xyz(dir + "/n.txt", "skip,skip,skip,x,y,z,skip").positions[1],
            Eigen::Vector3f(0, 1, 0));
  EXPECT_THROW(read_xyz(dir + "/n.txt", "x,y,z"), Error) << "3 columns given, 7 in the file";
  for (const char* bad : {"x,y,z,colour", "x,y,nx", "x,y,z,nx,ny", "x y z skip _ skip r"}) {
    try {
      read_xyz(dir + "/n.txt", bad);
      ADD_FAILURE() << bad;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("--columns"), std::string::npos) << e.what();
    }
  }
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

// A terrain tile in UTM (as national mapping agencies hand out ASCII XYZ): read in a local frame
// at whole kilometres, +z up; a point 2000 km away is an error naming its line.
TEST(XyzReader, MapCoordinatesGetALocalFrameWithZUp) {
  const std::string dir = test::temp_dir();
  test::write_file(dir + "/utm.xyz",
                   "500123.25 5401987.5 101.25\n500124.25 5401988.5 102.5\n500125.5 5401989 99\n");
  const PointCloud tile = read_xyz(dir + "/utm.xyz");
  ASSERT_EQ(tile.size(), 3u);
  EXPECT_EQ(tile.origin, Eigen::Vector3d(500000, 5402000, 0));
  EXPECT_TRUE(tile.z_up);
  EXPECT_EQ(tile.positions[1], Eigen::Vector3f(124.25f, -11.5f, 102.5f));  // exact in floats
  // Local coordinates: no frame, no flag.
  test::write_file(dir + "/local.xyz", "1 2 3\n4 5 6\n");
  const PointCloud local = read_xyz(dir + "/local.xyz");
  EXPECT_FALSE(local.z_up);
  EXPECT_TRUE(local.origin.isZero());
  test::write_file(dir + "/far.xyz", "500123 5401987 101\n2500123 5401987 101\n");
  try {
    read_xyz(dir + "/far.xyz");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("line 2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("more than 1e6 m from the first point"), std::string::npos)
        << e.what();
  }
  test::write_file(dir + "/garbage.xyz", "1e30 0 0\n");  // no position on Earth
  EXPECT_THROW(read_xyz(dir + "/garbage.xyz"), Error);
}

TEST(XyzReader, NaNRowsAreKeptForTheFilterToCount) {
  const PointCloud c = read_xyz(test::fixture("bad/nan_rows.xyz"));
  EXPECT_EQ(c.size(), 4u);
  for (const auto& p : c.positions) EXPECT_FALSE(p.allFinite());
}

}  // namespace
}  // namespace meshflow::io
