// Reading a point file by byte ranges (nodes/io/read_point_cloud.h, ply_reader.h): the ranges
// together give exactly the points of the whole read, in order, in its local frame; formats
// whose rows have no fixed size say why they cannot be split.

#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "nodes/io/byte_buffer.h"
#include "nodes/io/ply_point_writer.h"
#include "nodes/io/ply_reader.h"
#include "nodes/io/read_point_cloud.h"
#include "runtime/error.h"
#include "test_support.h"

namespace meshflow::io {
namespace {

// A binary PLY of `n` points far from the world origin (read in a local frame) with normals and
// colours.
std::string write_points(std::size_t n, const std::string& name) {
  const std::string path = test::temp_dir() + "/" + name;
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> u(-50.0f, 50.0f);
  PointCloud cloud;
  for (std::size_t i = 0; i < n; ++i) {  // 20 km out: read in a local frame
    cloud.positions.emplace_back(20000.0f + u(rng), 30000.0f + u(rng), 0.1f * u(rng));
    cloud.normals.emplace_back(0.0f, 0.0f, 1.0f);
    cloud.colors.push_back(Rgb8{static_cast<std::uint8_t>(i), 7, 9});
  }
  PlyPointWriter writer(path, n, true, true);
  writer.append(cloud);
  writer.finish();
  return path;
}

TEST(PointRanges, RangesOfABinaryPlyGiveTheWholeReadsPoints) {
  const std::string path = write_points(10007, "ranges.ply");
  const PointCloud whole = read_point_cloud(path);
  const PointRanges ranges = point_ranges(path, "");
  ASSERT_TRUE(ranges.by_byte_range) << ranges.why_not;
  ASSERT_EQ(ranges.points, whole.size());
  for (const std::uint64_t parts : {1u, 3u, 7u}) {
    PointCloud joined;
    for (std::uint64_t p = 0; p < parts; ++p) {
      const std::uint64_t first = ranges.points * p / parts;
      const std::uint64_t end = ranges.points * (p + 1) / parts;
      for_each_point_batch_in_range(path, "", first, end - first, 1000, [&](const PointCloud& b) {
        EXPECT_LE(b.size(), 1000u);
        EXPECT_EQ(b.origin, whole.origin) << "every range in the file's local frame";
        EXPECT_EQ(b.z_up, whole.z_up);
        joined.positions.insert(joined.positions.end(), b.positions.begin(), b.positions.end());
        joined.normals.insert(joined.normals.end(), b.normals.begin(), b.normals.end());
        joined.colors.insert(joined.colors.end(), b.colors.begin(), b.colors.end());
      });
    }
    EXPECT_EQ(joined.positions, whole.positions) << parts << " parts";
    EXPECT_EQ(joined.normals, whole.normals) << parts << " parts";
    EXPECT_EQ(joined.colors, whole.colors) << parts << " parts";
  }
  EXPECT_FALSE(whole.origin.isZero()) << "the test needs a local frame";
}

TEST(PointRanges, FormatsWithoutFixedRowsSayWhy) {
  const std::string dir = test::temp_dir();
  test::write_file(dir + "/a.ply",
                   "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                   "property float z\nend_header\n0 0 0\n1 0 0\n");
  const PointRanges ascii = point_ranges(dir + "/a.ply", "");
  EXPECT_FALSE(ascii.by_byte_range);
  EXPECT_NE(ascii.why_not.find("ASCII"), std::string::npos) << ascii.why_not;
  EXPECT_THROW(
      for_each_point_batch_in_range(dir + "/a.ply", "", 0, 1, 10, [](const PointCloud&) {}), Error);
  test::write_file(dir + "/a.xyz", "0 0 0\n1 0 0\n");
  const PointRanges text = point_ranges(dir + "/a.xyz", "");
  EXPECT_FALSE(text.by_byte_range);
  EXPECT_NE(text.why_not.find("line"), std::string::npos) << text.why_not;
  // A list property inside the vertex rows: no fixed row size either.
  std::string lists =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n"
      "property float y\nproperty float z\nproperty list uchar float junk\nend_header\n";
  lists += std::string(12, '\0') + std::string(1, '\0');
  test::write_file(dir + "/l.ply", lists);
  const PointRanges listed = point_ranges(dir + "/l.ply", "");
  EXPECT_FALSE(listed.by_byte_range);
  EXPECT_NE(listed.why_not.find("list"), std::string::npos) << listed.why_not;
}

TEST(PointRanges, ARangePastTheFileOrItsCountIsAnError) {
  const std::string path = write_points(100, "short.ply");
  EXPECT_THROW(for_each_point_batch_in_range(path, "", 90, 20, 10, [](const PointCloud&) {}),
               Error);
  // Cut the file: the rows the header declares are not all there.
  const std::vector<unsigned char> bytes = read_file_bytes(path);
  test::write_file(path, std::string(bytes.begin(), bytes.end() - 30));
  EXPECT_THROW(for_each_point_batch_in_range(path, "", 0, 10, 10, [](const PointCloud&) {}), Error);
}

}  // namespace
}  // namespace meshflow::io
