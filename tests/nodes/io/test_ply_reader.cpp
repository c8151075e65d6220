#include "nodes/io/ply_reader.h"

#include <gtest/gtest.h>

#include <cstring>

#include "fixtures/mesh_fixtures.h"
#include "nodes/io/mesh_writers.h"
#include "runtime/error.h"
#include "test_support.h"

namespace meshflow::io {
namespace {

template <typename T>
std::string bytes(T v, bool big_endian) {
  std::string s(sizeof(T), '\0');
  std::memcpy(s.data(), &v, sizeof(T));
  if (big_endian) std::reverse(s.begin(), s.end());
  return s;
}

// A file with an element before the vertices, extra scalar and list properties inside the
// vertex element, and a face element after it: the reader must skip all of them correctly.
std::string binary_ply(bool big) {
  std::string h =
      std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
      " 1.0\ncomment test\nelement camera 1\nproperty double fx\nproperty list uchar int ids\n"
      "element vertex 2\nproperty double x\nproperty float y\nproperty float z\n"
      "property short extra\nproperty list uchar float junk\nproperty float nx\n"
      "property float ny\nproperty float nz\nproperty uchar red\nproperty uchar green\n"
      "property uchar blue\nproperty float intensity\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  h += bytes(525.0, big) + bytes<std::uint8_t>(2, big) + bytes<std::int32_t>(7, big) +
       bytes<std::int32_t>(8, big);
  for (int i = 0; i < 2; ++i) {
    h += bytes(1.5 + i, big) + bytes(-2.0f, big) + bytes(3.25f, big) + bytes<std::int16_t>(-7, big);
    h += bytes<std::uint8_t>(static_cast<std::uint8_t>(i + 1), big);
    for (int k = 0; k <= i; ++k) h += bytes(9.0f, big);
    h += bytes(0.0f, big) + bytes(0.0f, big) + bytes(1.0f, big);
    h += std::string{static_cast<char>(10 + i), 20, static_cast<char>(200)} + bytes(0.5f, big);
  }
  h += bytes<std::uint8_t>(3, big) + bytes<std::int32_t>(0, big) + bytes<std::int32_t>(1, big) +
       bytes<std::int32_t>(0, big);
  return h;
}

void expect_two_vertices(const PointCloud& c) {
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.positions[1], Eigen::Vector3f(2.5f, -2.0f, 3.25f));
  ASSERT_TRUE(c.has_normals());
  EXPECT_EQ(c.normals[0], Eigen::Vector3f(0, 0, 1));
  ASSERT_TRUE(c.has_colors());
  EXPECT_EQ(c.colors[1], (Rgb8{11, 20, 200}));
  ASSERT_TRUE(c.has_intensities());
  EXPECT_EQ(c.intensities[0], 0.5f);
}

TEST(PlyReader, BinaryLittleAndBigEndianWithSkippedPropertiesAndElements) {
  const std::string dir = test::temp_dir();
  for (bool big : {false, true}) {
    const std::string path = dir + (big ? "/be.ply" : "/le.ply");
    test::write_file(path, binary_ply(big));
    expect_two_vertices(read_ply(path));
  }
}

TEST(PlyReader, AsciiWithListsAndCrLf) {
  const std::string path = test::temp_dir() + "/a.ply";
  test::write_file(
      path,
      "ply\r\nformat ascii 1.0\r\nelement vertex 2\r\nproperty float x\r\nproperty float y\r\n"
      "property float z\r\nproperty list uchar int junk\r\nproperty uchar red\r\n"
      "property uchar green\r\nproperty uchar blue\r\nend_header\r\n"
      "1 2 3 2 5 6 255 0 0\r\n4 5 6 0 0 255 0\r\n");
  const PointCloud c = read_ply(path);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.positions[1], Eigen::Vector3f(4, 5, 6));
  EXPECT_EQ(c.colors[0], (Rgb8{255, 0, 0}));
  EXPECT_FALSE(c.has_normals());
}

void expect_error(const std::string& file, const std::string& fragment) {
  const std::string path = test::fixture("bad/" + file);
  try {
    read_ply(path);
    FAIL() << "no error for " << file;
  } catch (const Error& e) {
    EXPECT_EQ(e.source(), path);
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(PlyReader, BrokenFilesGiveOneClearError) {
  expect_error("truncated_binary.ply", "file ends early");
  expect_error("count_too_large.ply", "file ends early");
  expect_error("count_too_small.ply", "counts do not match");
  expect_error("non_numeric.ply", "expected a number, got 'abc'");
  expect_error("empty.ply", "not a PLY file");
  expect_error("unknown_type.ply", "unknown property type 'float128'");
  expect_error("huge_coordinates.ply", "beyond");
  expect_error("huge_coordinates.ply", "vertex 1");
  expect_error("not_a_ply.ply", "not a PLY file");
}

// Map coordinates in doubles (as CloudCompare and PDAL write UTM clouds): a local frame at whole
// kilometres, +z up, positions exact to the file's millimetres.
TEST(PlyReader, MapCoordinatesInDoublesGetALocalFrameWithZUp) {
  const std::string path = test::temp_dir() + "/utm.ply";
  test::write_file(path,
                   "ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\n"
                   "property double y\nproperty double z\nend_header\n"
                   "612345.125 5801234.5 41.25\n612346.5 5801235.75 42\n");
  const PointCloud c = read_ply(path);
  EXPECT_EQ(c.origin, Eigen::Vector3d(612000, 5801000, 0));
  EXPECT_TRUE(c.z_up);
  EXPECT_EQ(c.positions[1], Eigen::Vector3f(346.5f, 235.75f, 42.0f));
}

// Rows without properties take no bytes: a binary element of 10^18 of them used to be read for
// ever (fuzz_ply's timeout, fuzz/regressions/ply/). Now a header error, at once.
TEST(PlyReader, ElementWithRowsButNoPropertiesIsAnError) {
  const std::string path = test::temp_dir() + "/no_properties.ply";
  test::write_file(path,
                   "ply\nformat binary_little_endian 1.0\nelement junk 1000000000000000000\n"
                   "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                   "end_header\n" +
                       std::string(12, '\0'));
  try {
    read_ply(path);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.location(), "element 'junk'");
    EXPECT_NE(std::string(e.what()).find("declares 1000000000000000000 rows but no properties"),
              std::string::npos)
        << e.what();
  }
  // Zero rows of nothing is harmless.
  test::write_file(path,
                   "ply\nformat ascii 1.0\nelement junk 0\nelement vertex 1\nproperty float x\n"
                   "property float y\nproperty float z\nend_header\n1 2 3\n");
  EXPECT_EQ(read_ply(path).size(), 1u);
}

TEST(PlyReader, MissingFileNamesThePath) { EXPECT_THROW(read_ply("/nonexistent/x.ply"), Error); }

// Fuzz-style corruption: every truncation and many byte flips of a valid file either parse or
// throw meshflow::Error; nothing else escapes (ASan/UBSan in CI catch memory errors).
TEST(PlyReader, TruncationsAndByteFlipsNeverCrash) {
  const std::string good = binary_ply(false);
  const std::string path = test::temp_dir() + "/fuzz.ply";
  for (std::size_t len = 0; len < good.size(); len += 3) {
    test::write_file(path, good.substr(0, len));
    EXPECT_THROW(read_ply(path), Error) << "length " << len;
  }
  std::uint32_t state = 12345;
  for (int trial = 0; trial < 300; ++trial) {
    test::write_file(path, test::flip_bytes(good, 3, state));
    try {
      read_ply(path);
    } catch (const Error&) {
    }
  }
}

// The same corruption against the mesh reader (faces: list counts and vertex indices are the
// fields a flipped byte breaks), for both encodings; a valid result must index its vertices.
TEST(PlyReader, MeshTruncationsAndByteFlipsNeverCrash) {
  TriangleMesh mesh;
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  compute_vertex_normals(mesh);
  const std::string path = test::temp_dir() + "/fuzz_mesh.ply";
  for (auto encoding : {PlyEncoding::kBinary, PlyEncoding::kAscii}) {
    write_ply(path, mesh, encoding);
    const std::string good = test::read_file(path);
    auto parse_or_error = [&](const std::string& contents) {
      test::write_file(path, contents);
      try {
        const TriangleMesh m = read_ply_mesh(path);
        for (const Triangle& t : m.triangles)
          for (std::uint32_t v : t) EXPECT_LT(v, m.vertices.size());
      } catch (const Error&) {
      }
    };
    for (std::size_t len = 0; len < good.size(); ++len) parse_or_error(good.substr(0, len));
    std::uint32_t state = 777;
    for (int trial = 0; trial < 300; ++trial) parse_or_error(test::flip_bytes(good, 2, state));
  }
}

TEST(PlyMeshReader, RoundTripsWrittenMeshesAndRejectsBadFaces) {
  const std::string dir = test::temp_dir();
  TriangleMesh mesh = test::grid_patch(3, true);
  compute_vertex_normals(mesh);
  for (auto enc : {PlyEncoding::kBinary, PlyEncoding::kAscii}) {
    write_ply(dir + "/m.ply", mesh, enc);
    const TriangleMesh back = read_ply_mesh(dir + "/m.ply");
    EXPECT_EQ(back.vertices, mesh.vertices);
    EXPECT_EQ(back.triangles, mesh.triangles);
    EXPECT_EQ(back.normals.size(), mesh.normals.size());
  }
  test::write_file(dir + "/bad.ply",
                   "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                   "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                   "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
  try {
    read_ply_mesh(dir + "/bad.ply");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("face 0"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("vertex index"), std::string::npos) << e.what();
  }
  // Point clouds (no face element) read as meshes without triangles.
  test::write_file(dir + "/pts.ply",
                   "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                   "property float z\nend_header\n1 2 3\n");
  EXPECT_TRUE(read_ply_mesh(dir + "/pts.ply").triangles.empty());
}

}  // namespace
}  // namespace meshflow::io
