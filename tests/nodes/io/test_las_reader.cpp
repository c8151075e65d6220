#include "nodes/io/las_reader.h"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "nodes/io/read_point_cloud.h"
#include "runtime/error.h"
#include "test_support.h"

namespace meshflow::io {
namespace {

// A LAS file laid out as the ASPRS specification says: a 1.2 (227-byte) or 1.4 (375-byte)
// header, no VLRs, then `points` records of the given format holding (i, 2i, -i) mm-scaled
// coordinates plus an offset, intensity 100 + i and colour (i, 2i, 3i) x `colour_scale`.
std::string las_file(int minor, int format, std::uint16_t record_length, std::uint32_t points,
                     std::uint16_t colour_scale = 256, double offset = 10.0) {
  const std::uint16_t header_size = minor >= 4 ? 375 : 227;
  std::string h(header_size, '\0');
  const auto put = [&h](std::size_t at, const auto& v) { std::memcpy(&h[at], &v, sizeof v); };
  std::memcpy(&h[0], "LASF", 4);
  h[24] = 1;
  h[25] = static_cast<char>(minor);
  put(94, header_size);
  put(96, static_cast<std::uint32_t>(header_size));
  h[104] = static_cast<char>(format);
  put(105, record_length);
  put(107, minor >= 4 ? std::uint32_t{0} : points);  // 1.4 files may leave the legacy count 0
  for (int k = 0; k < 3; ++k) {
    put(131 + 8 * k, 0.001);
    put(155 + 8 * k, offset);
  }
  if (minor >= 4) put(247, std::uint64_t{points});
  const int rgb_at = format == 2 ? 20 : format == 3 ? 28 : format >= 7 ? 30 : -1;
  for (std::uint32_t i = 0; i < points; ++i) {
    std::string r(record_length, '\0');
    const std::int32_t xyz[3] = {static_cast<std::int32_t>(i), static_cast<std::int32_t>(2 * i),
                                 -static_cast<std::int32_t>(i)};
    std::memcpy(&r[0], xyz, 12);
    const auto intensity = static_cast<std::uint16_t>(100 + i);
    std::memcpy(&r[12], &intensity, 2);
    if (rgb_at >= 0)
      for (std::uint32_t c = 0; c < 3; ++c) {
        const auto v = static_cast<std::uint16_t>((c + 1) * i * colour_scale);
        std::memcpy(&r[static_cast<std::size_t>(rgb_at) + 2 * c], &v, 2);
      }
    h += r;
  }
  return h;
}

TEST(LasReader, FormatsZeroToThreeAndSixToEight) {
  const std::string dir = test::temp_dir();
  const struct {
    int minor, format;
    std::uint16_t length;
  } cases[] = {{2, 0, 20}, {2, 1, 28}, {2, 2, 26}, {3, 3, 34},
               {4, 6, 30}, {4, 7, 36}, {4, 8, 38}, {2, 3, 40}};  // the last with extra bytes
  for (const auto& c : cases) {
    SCOPED_TRACE("format " + std::to_string(c.format));
    const std::string path = dir + "/f.las";
    test::write_file(path, las_file(c.minor, c.format, c.length, 50));
    const PointCloud cloud = read_point_cloud(path);
    ASSERT_EQ(cloud.size(), 50u);
    EXPECT_NEAR(cloud.positions[7].x(), 10.007f, 1e-5f);
    EXPECT_NEAR(cloud.positions[7].y(), 10.014f, 1e-5f);
    EXPECT_NEAR(cloud.positions[7].z(), 9.993f, 1e-5f);
    EXPECT_EQ(cloud.intensities[7], 107.0f);
    const bool rgb = c.format == 2 || c.format == 3 || c.format >= 7;
    ASSERT_EQ(cloud.has_colors(), rgb);
    if (rgb) {
      EXPECT_EQ(cloud.colors[7], (Rgb8{7, 14, 21}));  // 16-bit channels scaled down
    }
  }
  test::write_file(dir + "/8bit.las", las_file(2, 2, 26, 50, 1));
  EXPECT_EQ(read_las(dir + "/8bit.las").colors[7], (Rgb8{7, 14, 21})) << "8-bit values kept";
}

// UTM-like coordinates (5 000 km): read in a local frame whose origin is the first point
// rounded to kilometres, so the float positions keep the file's millimetres.
TEST(LasReader, GeoreferencedFilesAreReadInALocalFrame) {
  const std::string dir = test::temp_dir();
  test::write_file(dir + "/utm.las", las_file(2, 3, 34, 50, 256, 5000123.0));
  const PointCloud c = read_las(dir + "/utm.las");
  EXPECT_EQ(c.origin, Eigen::Vector3d(5000000.0, 5000000.0, 5000000.0));
  ASSERT_EQ(c.size(), 50u);
  for (std::size_t i = 0; i < c.size(); ++i) {
    const Eigen::Vector3d expected(123.0 + 0.001 * i, 123.0 + 0.002 * i, 123.0 - 0.001 * i);
    EXPECT_LT((c.positions[i].cast<double>() - expected).norm(), 2e-5) << i;
  }
  // Near the world origin nothing changes.
  test::write_file(dir + "/local.las", las_file(2, 0, 20, 3));
  EXPECT_TRUE(read_las(dir + "/local.las").origin.isZero());
}

TEST(LasReader, BatchesAreTheWholeCloudInPiecesWithOneOrigin) {
  const std::string path = test::temp_dir() + "/batches.las";
  test::write_file(path, las_file(2, 3, 34, 50, 256, 5000123.0));  // 16-bit colours, UTM
  const PointCloud whole = read_las(path);
  PointCloud joined;
  std::size_t pieces = 0;
  read_las_batches(path, 16, [&](const PointCloud& piece) {
    EXPECT_LE(piece.size(), 16u);
    EXPECT_EQ(piece.origin, whole.origin);
    ++pieces;
    joined.positions.insert(joined.positions.end(), piece.positions.begin(), piece.positions.end());
    joined.colors.insert(joined.colors.end(), piece.colors.begin(), piece.colors.end());
    joined.intensities.insert(joined.intensities.end(), piece.intensities.begin(),
                              piece.intensities.end());
  });
  EXPECT_EQ(pieces, 4u);
  EXPECT_EQ(joined.positions, whole.positions);
  EXPECT_EQ(joined.colors, whole.colors) << "colour scaling decided over the whole file";
  EXPECT_EQ(joined.intensities, whole.intensities);
}

TEST(LasReader, BadFilesAreClearErrorsBeforeAnyAllocation) {
  const std::string dir = test::temp_dir();
  std::string huge = las_file(2, 0, 20, 3);
  const std::uint32_t claimed = 4000000000u;
  std::memcpy(&huge[107], &claimed, 4);
  std::string laz = las_file(2, 0, 20, 3);
  laz[104] = static_cast<char>(0x80 | 3);
  std::string short_record = las_file(2, 3, 34, 3);
  short_record[105] = 20;
  std::string far = las_file(2, 0, 20, 3);
  const std::int32_t far_x = 2000000000;  // 2e6 m at 1 mm: 2000 km from the first point
  std::memcpy(&far[227 + 20], &far_x, 4);
  const std::pair<std::string, std::string> bad[] = {
      {"huge.las", huge},
      {"laz.las", laz},
      {"format.las", las_file(2, 4, 57, 3)},
      {"record.las", short_record},
      {"truncated.las", las_file(2, 0, 20, 3).substr(0, 227 + 30)},
      {"signature.las", "LASX" + las_file(2, 0, 20, 3).substr(4)},
      {"short.las", "LASF"},
      {"far.las", far}};
  const char* expected[] = {
      "more than the file", "LAZ",  "format 4", "shorter",
      "truncated",          "LASF", "LASF",     "more than 1e6 m from the first point"};
  for (std::size_t i = 0; i < std::size(bad); ++i) {
    const std::string path = dir + "/" + bad[i].first;
    test::write_file(path, bad[i].second);
    try {
      read_las(path);
      ADD_FAILURE() << bad[i].first;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(expected[i]), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(read_point_cloud(dir + "/x.laz"), Error);
}

// Found by fuzz/fuzz_las.cpp (fuzz/regressions/las/): records of up to 64 KiB were read 65 536
// at a time, a 4 GiB buffer for a 317-byte file. Chunks are now ~4 MiB and never more than the
// file holds.
TEST(LasReader, LongRecordsAreReadInChunksTheFileCanHold) {
  const std::string dir = test::temp_dir();
  test::write_file(dir + "/long.las", las_file(2, 0, 65535, 70));
  const PointCloud cloud = read_las(dir + "/long.las");
  ASSERT_EQ(cloud.size(), 70u);
  EXPECT_FLOAT_EQ(cloud.positions[69].y(), 10.0f + 0.138f);
  test::write_file(dir + "/empty.las", las_file(2, 0, 65535, 0));
  EXPECT_EQ(read_las(dir + "/empty.las").size(), 0u);
  EXPECT_EQ(
      read_las(std::string(MESHFLOW_SOURCE_DIR) + "/fuzz/regressions/las/oom_long_records.las")
          .size(),
      0u);
}

TEST(LasReader, MutatedFilesNeverCrash) {
  const std::string good = las_file(4, 7, 36, 40);
  const std::string path = test::temp_dir() + "/m.las";
  std::uint32_t state = 11;
  for (int i = 0; i < 300; ++i) {
    test::write_file(path, test::mutate(good, state));
    try {
      const PointCloud c = read_las(path);
      EXPECT_LE(c.size(), 40u * 36u);
    } catch (const Error&) {
    }
  }
}

}  // namespace
}  // namespace meshflow::io
