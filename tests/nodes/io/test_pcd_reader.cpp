#include "nodes/io/pcd_reader.h"

#include <gtest/gtest.h>
#include <lzf.h>

#include <cmath>
#include <cstring>

#include "runtime/error.h"
#include "test_support.h"

namespace meshflow::io {
namespace {

float packed_rgb(std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  const std::uint32_t bits = (std::uint32_t{r} << 16) | (std::uint32_t{g} << 8) | b;
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

TEST(PcdReader, AsciiWithNormalsAndExtraField) {
  const std::string path = test::temp_dir() + "/a.pcd";
  test::write_file(
      path,
      "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z normal_x normal_y normal_z curvature\n"
      "SIZE 4 4 4 4 4 4 4\nTYPE F F F F F F F\nCOUNT 1 1 1 1 1 1 1\nWIDTH 2\nHEIGHT 1\n"
      "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n1 2 3 0 0 1 0.1\n4 5 6 1 0 0 0.2\n");
  const PointCloud c = read_pcd(path);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.positions[1], Eigen::Vector3f(4, 5, 6));
  EXPECT_EQ(c.normals[0], Eigen::Vector3f(0, 0, 1));
  EXPECT_FALSE(c.is_organized());
}

std::string binary_header(const char* data, int w, int h) {
  return "VERSION 0.7\nFIELDS x y z pad rgb intensity\nSIZE 4 4 4 2 4 4\nTYPE F F F U F F\n"
         "COUNT 1 1 1 2 1 1\nWIDTH " +
         std::to_string(w) + "\nHEIGHT " + std::to_string(h) + "\nPOINTS " + std::to_string(w * h) +
         "\nDATA " + data + "\n";
}

struct Row {
  float x, y, z;
  std::uint16_t pad[2];
  float rgb, intensity;
};

std::vector<Row> organized_rows() {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  return {{0, 0, 1, {0, 0}, packed_rgb(255, 0, 0), 1},
          {nan, nan, nan, {0, 0}, packed_rgb(0, 0, 0), 0},
          {1, 0, 1, {7, 7}, packed_rgb(0, 255, 0), 2},
          {1, 1, 1, {0, 0}, packed_rgb(1, 2, 3), 3}};
}

void expect_organized(const PointCloud& c) {
  ASSERT_EQ(c.size(), 4u);
  EXPECT_TRUE(c.is_organized());
  EXPECT_EQ(c.width, 2u);
  EXPECT_TRUE(std::isnan(c.positions[1].x()));
  EXPECT_EQ(c.positions[2], Eigen::Vector3f(1, 0, 1));
  EXPECT_EQ(c.colors[3], (Rgb8{1, 2, 3}));
  EXPECT_EQ(c.intensities[2], 2.0f);
}

// A binary PCD of organized_rows(): header and rows.
std::string binary_pcd() {
  std::string body;
  for (const Row& r : organized_rows()) {
    body.append(reinterpret_cast<const char*>(&r.x), 12);
    body.append(reinterpret_cast<const char*>(r.pad), 4);
    body.append(reinterpret_cast<const char*>(&r.rgb), 8);
  }
  return binary_header("binary", 2, 2) + body;
}

// A binary_compressed PCD of organized_rows(): header, block sizes, LZF block (field-major: all
// x, all y, all z, all pad, all rgb, all intensity).
std::string compressed_pcd() {
  const auto rows = organized_rows();
  std::string raw;
  for (int f = 0; f < 6; ++f) {
    for (const Row& r : rows) {
      const float* fl[] = {&r.x, &r.y, &r.z, nullptr, &r.rgb, &r.intensity};
      if (f == 3)
        raw.append(reinterpret_cast<const char*>(r.pad), 4);
      else
        raw.append(reinterpret_cast<const char*>(fl[f]), 4);
    }
  }
  std::string packed(raw.size() * 2 + 16, '\0');
  const unsigned n = lzf_compress(raw.data(), static_cast<unsigned>(raw.size()), packed.data(),
                                  static_cast<unsigned>(packed.size()));
  EXPECT_GT(n, 0u);
  const std::uint32_t sizes[2] = {n, static_cast<std::uint32_t>(raw.size())};
  return binary_header("binary_compressed", 2, 2) +
         std::string(reinterpret_cast<const char*>(sizes), 8) + packed.substr(0, n);
}

TEST(PcdReader, BinaryOrganizedWithNaNAndPackedColour) {
  const std::string path = test::temp_dir() + "/b.pcd";
  test::write_file(path, binary_pcd());
  expect_organized(read_pcd(path));
}

TEST(PcdReader, BinaryCompressedFieldMajor) {
  const std::string path = test::temp_dir() + "/c.pcd";
  test::write_file(path, compressed_pcd() + std::string(100, '\0'));
  expect_organized(read_pcd(path));
}

TEST(PcdReader, NormalsInEveryEncodingAndNaNNormalsKept) {
  // Two points with normal_x normal_y normal_z; the second normal NaN (the normals stage
  // estimates it).
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float values[2][6] = {{1, 2, 3, 0, 0, 1}, {4, 5, 6, nan, nan, nan}};
  const std::string header =
      "VERSION 0.7\nFIELDS x y z normal_x normal_y normal_z\nSIZE 4 4 4 4 4 4\n"
      "TYPE F F F F F F\nCOUNT 1 1 1 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ";
  std::string rows, columns;
  for (const auto& row : values) rows.append(reinterpret_cast<const char*>(row), 24);
  for (int f = 0; f < 6; ++f)
    for (const auto& row : values) columns.append(reinterpret_cast<const char*>(&row[f]), 4);
  std::string packed(columns.size() * 2 + 16, '\0');
  const unsigned n = lzf_compress(columns.data(), static_cast<unsigned>(columns.size()),
                                  packed.data(), static_cast<unsigned>(packed.size()));
  ASSERT_GT(n, 0u);
  const std::uint32_t sizes[2] = {n, static_cast<std::uint32_t>(columns.size())};
  const std::string files[] = {
      header + "ascii\n1 2 3 0 0 1\n4 5 6 nan nan nan\n", header + "binary\n" + rows,
      header + "binary_compressed\n" + std::string(reinterpret_cast<const char*>(sizes), 8) +
          packed.substr(0, n)};
  for (const std::string& file : files) {
    const std::string path = test::temp_dir() + "/n.pcd";
    test::write_file(path, file);
    const PointCloud c = read_pcd(path);
    ASSERT_EQ(c.normals.size(), 2u);
    EXPECT_EQ(c.normals[0], Eigen::Vector3f(0, 0, 1));
    EXPECT_TRUE(std::isnan(c.normals[1].x()));
  }
}

TEST(PcdReader, ANonZeroViewpointIsTheSensorPosition) {
  const std::string path = test::temp_dir() + "/v.pcd";
  auto with_viewpoint = [&](const std::string& viewpoint) {
    test::write_file(path,
                     "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                     "WIDTH 1\nHEIGHT 1\nVIEWPOINT " +
                         viewpoint + "\nPOINTS 1\nDATA ascii\n1 2 3\n");
    return read_pcd(path);
  };
  const PointCloud seen = with_viewpoint("0.5 -1 2 1 0 0 0");
  EXPECT_TRUE(seen.has_sensor_origin);
  EXPECT_EQ(seen.sensor_origin, Eigen::Vector3f(0.5f, -1.0f, 2.0f));
  EXPECT_FALSE(with_viewpoint("0 0 0 0 1 0 0").has_sensor_origin);  // PCL's "none"
  EXPECT_THROW(with_viewpoint("0 0 nan 1 0 0 0"), Error);
  EXPECT_THROW(with_viewpoint("0 0 0"), Error);
}

// Headers that declare more data than the file holds are refused before the reader allocates
// for them: a lying header must not exhaust memory (under ASan such an allocation aborts).
TEST(PcdReader, LyingHeadersAreRefusedBeforeAllocating) {
  const std::string path = test::temp_dir() + "/lying.pcd";
  const auto error_of = [&](const std::string& contents) -> std::string {
    test::write_file(path, contents);
    try {
      read_pcd(path);
    } catch (const Error& e) {
      return e.what();
    }
    return "no error";
  };
  const std::string xyz = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n";
  const std::string row(12, '\0');
  EXPECT_NE(error_of(xyz + "COUNT 1 1 1\nWIDTH 4000000000\nHEIGHT 1\nDATA binary\n" + row)
                .find("file ends early"),
            std::string::npos);
  EXPECT_NE(error_of(xyz + "COUNT 1 1 4294967295\nWIDTH 1\nHEIGHT 1\nDATA binary\n" + row)
                .find("invalid COUNT"),
            std::string::npos);
  EXPECT_NE(error_of(xyz + "COUNT 1 1 1\nWIDTH 18446744073709551615\nHEIGHT 2\nDATA binary\n")
                .find("overflows"),
            std::string::npos);
  const auto compressed = [&](std::uint32_t packed, std::uint32_t unpacked) {
    const std::uint32_t sizes[2] = {packed, unpacked};
    return error_of(xyz + "COUNT 1 1 1\nWIDTH 1\nHEIGHT 1\nDATA binary_compressed\n" +
                    std::string(reinterpret_cast<const char*>(sizes), 8) + row);
  };
  EXPECT_NE(compressed(4000000000u, 12).find("file ends early"), std::string::npos);
  EXPECT_NE(compressed(12, 4000000000u).find("cannot come from"), std::string::npos);
}

// Fuzz-style corruption of binary and binary_compressed files: every truncation, byte flips,
// and every header number replaced by extreme values either parse or throw meshflow::Error.
TEST(PcdReader, TruncationsFlipsAndExtremeHeaderNumbersNeverCrash) {
  const std::string path = test::temp_dir() + "/fuzz.pcd";
  const auto parse_or_error = [&](const std::string& contents) {
    test::write_file(path, contents);
    try {
      const PointCloud c = read_pcd(path);
      EXPECT_LE(c.size(), contents.size());
    } catch (const Error&) {
    }
  };
  for (const std::string& good : {binary_pcd(), compressed_pcd()}) {
    for (std::size_t len = 0; len < good.size(); ++len) parse_or_error(good.substr(0, len));
    std::uint32_t state = 4242;
    for (int trial = 0; trial < 200; ++trial) parse_or_error(test::flip_bytes(good, 2, state));
    const std::size_t header_end = good.find("DATA");
    for (std::size_t at = good.find_first_of("0123456789"); at < header_end;
         at = good.find_first_of("0123456789", good.find_first_not_of("0123456789.", at))) {
      const std::size_t len = good.find_first_not_of("0123456789.", at) - at;
      for (const char* extreme : {"0", "4294967295", "18446744073709551615", "4000000000"})
        parse_or_error(good.substr(0, at) + extreme + good.substr(at + len));
    }
  }
}

// A coordinate beyond +-1e6 m names the point (binary and compressed: the location is only
// formatted for the error).
TEST(PcdReader, HugeCoordinatesNameThePoint) {
  auto rows = organized_rows();
  rows[2].y = 3e7f;
  std::string body;
  for (const Row& r : rows) {
    body.append(reinterpret_cast<const char*>(&r.x), 12);
    body.append(reinterpret_cast<const char*>(r.pad), 4);
    body.append(reinterpret_cast<const char*>(&r.rgb), 8);
  }
  const std::string path = test::temp_dir() + "/huge.pcd";
  test::write_file(path, binary_header("binary", 2, 2) + body);
  try {
    read_pcd(path);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.source(), path);
    EXPECT_NE(std::string(e.what()).find("point 2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("beyond"), std::string::npos) << e.what();
  }
}

TEST(PcdReader, BrokenFilesGiveOneClearError) {
  for (const char* name : {"empty.pcd", "truncated.pcd", "inconsistent_header.pcd"}) {
    const std::string path = test::fixture(std::string("bad/") + name);
    try {
      read_pcd(path);
      FAIL() << name;
    } catch (const Error& e) {
      EXPECT_EQ(e.source(), path);
    }
  }
}

TEST(PcdReader, RealKinectFramesAndBunny) {
  MESHFLOW_REQUIRE_DATA("kinect_pcl/office1.pcd");
  const PointCloud office = read_pcd(test::data_path("kinect_pcl/office1.pcd"));
  EXPECT_EQ(office.size(), 307200u);
  EXPECT_TRUE(office.is_organized());
  const std::size_t finite = count_finite_points(office);
  EXPECT_EQ(finite, 254456u);
  const PointCloud mug =
      read_pcd(test::data_path("kinect_pcl/table_scene_mug_stereo_textured.pcd"));
  EXPECT_EQ(count_finite_points(mug), 209280u);
  ASSERT_TRUE(mug.has_colors());
  const PointCloud bun0 = read_pcd(test::data_path("objects/bun0.pcd"));
  EXPECT_EQ(bun0.size(), 397u);
  ASSERT_TRUE(bun0.has_normals());
  EXPECT_NEAR(bun0.normals[0].norm(), 1.0f, 1e-4f);
  EXPECT_EQ(read_pcd(test::data_path("objects/bunny.pcd")).size(), 397u);
}

}  // namespace
}  // namespace meshflow::io
