#include "nodes/io/mesh_writers.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "nodes/io/ply_reader.h"
#include "runtime/error.h"
#include "test_support.h"

namespace meshflow::io {
namespace {

TriangleMesh sample_mesh() {
  TriangleMesh m;
  m.vertices = {{0.125f, -1.5f, 2}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}};
  m.colors = {{1, 2, 3}, {4, 5, 6}, {7, 8, 9}};
  compute_vertex_normals(m);
  return m;
}

// The optional `quality` vertex property: after the colours, one float per vertex; other
// readers (and meshflow's) still read the rest of the file.
TEST(MeshWriters, PlyQualityPropertyFollowsTheColours) {
  const TriangleMesh m = sample_mesh();
  const std::string dir = test::temp_dir();
  const std::vector<VertexScalar> quality = {{"quality", {0.25f, 0.5f, 0.001f}},
                                             {"observations", {12.0f, 3.0f, 0.0f}}};
  write_ply(dir + "/q.ply", m, PlyEncoding::kAscii, Eigen::Vector3d::Zero(), quality);
  const std::string text = test::read_file(dir + "/q.ply");
  EXPECT_NE(text.find("property uchar blue\nproperty float quality\nproperty float "
                      "observations\nelement face"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find(" 7 8 9 0.001 0\n"), std::string::npos) << text;
  for (PlyEncoding enc : {PlyEncoding::kBinary, PlyEncoding::kAscii}) {
    write_ply(dir + "/q.ply", m, enc, Eigen::Vector3d::Zero(), quality);
    const TriangleMesh back = read_ply_mesh(dir + "/q.ply");
    EXPECT_EQ(back.vertices, m.vertices);
    EXPECT_EQ(back.colors, m.colors);
    EXPECT_EQ(back.triangles, m.triangles);
  }
  EXPECT_THROW(write_ply(dir + "/bad.ply", m, PlyEncoding::kBinary, Eigen::Vector3d::Zero(),
                         {{"quality", {1.0f}}}),
               Error);
  EXPECT_THROW(write_ply(dir + "/bad.ply", m, PlyEncoding::kBinary, Eigen::Vector3d::Zero(),
                         {{"two words", {1.0f, 2.0f, 3.0f}}}),
               Error);
  EXPECT_FALSE(std::filesystem::exists(dir + "/bad.ply"));
}

TEST(MeshWriters, PlyRoundTripBinaryAndAscii) {
  const TriangleMesh m = sample_mesh();
  const std::string dir = test::temp_dir();
  for (PlyEncoding enc : {PlyEncoding::kBinary, PlyEncoding::kAscii}) {
    const std::string path = dir + (enc == PlyEncoding::kBinary ? "/b.ply" : "/a.ply");
    write_ply(path, m, enc);
    const PointCloud c = read_ply(path);  // reads the vertex element, skips faces
    ASSERT_EQ(c.size(), 3u);
    for (std::size_t i = 0; i < 3; ++i) {
      EXPECT_EQ(c.positions[i], m.vertices[i]);
      EXPECT_TRUE(c.normals[i].isApprox(m.normals[i], 1e-6f));
      EXPECT_EQ(c.colors[i], m.colors[i]);
    }
    EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  }
}

TEST(MeshWriters, ObjHasOneBasedFaces) {
  const std::string path = test::temp_dir() + "/m.obj";
  write_obj(path, sample_mesh());
  std::ifstream in(path);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("f 1//1 2//2 3//3"), std::string::npos);
  EXPECT_NE(text.find("v 0.125 -1.5 2"), std::string::npos);
}

TEST(MeshWriters, UnwritableOrUnknownOutputIsAnError) {
  EXPECT_THROW(write_mesh("/nonexistent-dir/m.ply", sample_mesh()), Error);
  EXPECT_THROW(write_mesh(test::temp_dir() + "/m.vrml", sample_mesh()), Error);
  try {
    write_mesh("/nonexistent-dir/m.ply", sample_mesh());
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("No such file or directory"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace meshflow::io
