// Round trips through every mesh format meshflow writes and reads (PLY, OBJ, OFF, STL, glTF
// binary), and the readers' errors on malformed and hostile files.

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <nlohmann/json.hpp>

#include "nodes/io/glb_reader.h"
#include "nodes/io/glb_writer.h"
#include "nodes/io/mesh_readers.h"
#include "nodes/io/mesh_writers.h"
#include "runtime/error.h"
#include "test_support.h"

namespace meshflow::io {
namespace {

// A closed coloured mesh with normals: the tetrahedron with a colour per vertex.
TriangleMesh coloured_tetrahedron() {
  TriangleMesh m = test::tetrahedron();
  for (std::size_t i = 0; i < m.vertices.size(); ++i)
    m.colors.push_back(
        {static_cast<std::uint8_t>(40 * i), 200, static_cast<std::uint8_t>(255 - i)});
  compute_vertex_normals(m);
  return m;
}

// Same vertex count and the same corner positions triangle by triangle (STL renumbers the
// vertices in order of first appearance, the other formats keep the numbering).
void expect_same_geometry(const TriangleMesh& a, const TriangleMesh& b) {
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  ASSERT_EQ(a.triangles.size(), b.triangles.size());
  for (std::size_t t = 0; t < a.triangles.size(); ++t)
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(a.vertices[a.triangles[t][c]], b.vertices[b.triangles[t][c]]) << t;
}

TEST(MeshFormats, EveryWriterRoundTripsThroughReadMesh) {
  const TriangleMesh m = coloured_tetrahedron();
  const std::string dir = test::temp_dir();
  for (const char* ext : {".ply", ".obj", ".off", ".stl", ".glb"}) {
    SCOPED_TRACE(ext);
    const std::string path = dir + "/m" + ext;
    write_mesh(path, m);
    const TriangleMesh back = read_mesh(path);
    expect_same_geometry(m, back);
    if (std::string(ext) != ".stl") {
      ASSERT_EQ(back.colors.size(), m.colors.size());
      for (std::size_t i = 0; i < m.colors.size(); ++i) EXPECT_EQ(back.colors[i], m.colors[i]);
    }
    if (std::string(ext) == ".ply" || std::string(ext) == ".obj" || std::string(ext) == ".glb") {
      ASSERT_EQ(back.normals.size(), m.normals.size());
      EXPECT_TRUE(back.normals[0].isApprox(m.normals[0], 1e-6f));
    }
  }
}

TEST(MeshFormats, StlWeldsCornersAndKeepsAClosedMeshClosed) {
  const TriangleMesh grid = test::grid_mesh(6);
  const std::string path = test::temp_dir() + "/grid.stl";
  write_stl(path, grid);
  EXPECT_EQ(test::read_file(path).size(), 84 + 50 * grid.triangles.size());
  const TriangleMesh back = read_stl_mesh(path);
  EXPECT_EQ(back.vertices.size(), grid.vertices.size());
  EXPECT_EQ(back.triangles.size(), grid.triangles.size());
  const TriangleMesh tet = read_mesh((write_stl(path, test::tetrahedron()), path));
  EXPECT_TRUE(edge_statistics(tet).closed());
}

TEST(MeshFormats, AsciiStlAndPolygonalObjAndOffAreTriangulated) {
  const std::string dir = test::temp_dir();
  test::write_file(dir + "/a.stl",
                   "solid t\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n"
                   "   vertex 0 1 0\n  endloop\n endfacet\n facet normal 0 0 1\n  outer loop\n"
                   "   vertex 1 0 0\n   vertex 1 1 0\n   vertex 0 1 0\n  endloop\n endfacet\n"
                   "endsolid t\n");
  TriangleMesh m = read_mesh(dir + "/a.stl");
  EXPECT_EQ(m.vertices.size(), 4u);
  EXPECT_EQ(m.triangles.size(), 2u);
  // A quad with texture coordinates and negative (relative) indices, a comment, a group.
  test::write_file(dir + "/q.obj",
                   "# quad\ng side\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nf -4/1 -3/1 -2/1 "
                   "-1/1\n");
  m = read_mesh(dir + "/q.obj");
  EXPECT_EQ(m.triangles.size(), 2u);
  EXPECT_TRUE(m.normals.empty());
  EXPECT_EQ(m.triangles[1], (Triangle{0, 2, 3}));
  test::write_file(dir + "/p.off",
                   "OFF\n# a pentagon\n5 1 0\n0 0 0\n1 0 0\n1.5 1 0\n0.5 1.5 0\n"
                   "-0.5 1 0\n5 0 1 2 3 4\n");
  m = read_mesh(dir + "/p.off");
  EXPECT_EQ(m.triangles.size(), 3u);
}

// Each bad file gives one meshflow::Error naming the file (and the line where there is one).
TEST(MeshFormats, MalformedAndHostileFilesAreClearErrors) {
  const std::string dir = test::temp_dir();
  const struct {
    const char* name;
    std::string content;
    const char* expected;
  } cases[] = {
      {"index.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\n", "line 3"},
      {"zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "vertex index 0"},
      {"nan.obj", "v nan 0 0\n", "finite"},
      {"short.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", "at least 3"},
      {"huge.off", "OFF\n1000000000000 1 0\n0 0 0\n", "more than the file"},
      {"early.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n# a comment long enough\n", "ends early"},
      {"badindex.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "vertex index 7"},
      {"keyword.off", "PLY\n3 1 0\n", "expected OFF"},
      {"truncated.stl", std::string(84, '\0') + "xx", "not an STL file"},
      {"facet.stl",
       "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\n"
       "endfacet\n",
       "2 vertices"},
      {"open.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n", "ends inside"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string path = dir + "/" + c.name;
    test::write_file(path, c.content);
    try {
      read_mesh(path);
      ADD_FAILURE() << "no error";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.expected), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(read_mesh(dir + "/missing.obj"), Error);
  EXPECT_THROW(read_mesh(dir + "/mesh.vrml"), Error);
}

// Mutated copies of valid files in each format: an error or a mesh, never a crash (the ASan
// build runs this).
TEST(MeshFormats, MutatedFilesNeverCrash) {
  const std::string dir = test::temp_dir();
  const TriangleMesh m = coloured_tetrahedron();
  std::uint32_t state = 7;
  for (const char* ext : {".obj", ".off", ".stl", ".glb"}) {
    const std::string good = dir + "/good" + ext;
    write_mesh(good, m);
    const std::string bytes = test::read_file(good);
    for (int i = 0; i < 200; ++i) {
      const std::string path = dir + "/mutated" + ext;
      test::write_file(path, test::mutate(bytes, state));
      try {
        const TriangleMesh back = read_mesh(path);
        for (const Triangle& t : back.triangles)
          for (std::uint32_t v : t) ASSERT_LT(v, back.vertices.size());
      } catch (const Error&) {
      }
    }
  }
}

template <typename T>
T read_at(const std::vector<std::uint8_t>& bytes, std::size_t at) {
  T value;
  std::memcpy(&value, bytes.data() + at, sizeof(T));
  return value;
}

// The .glb container and its JSON as the glTF 2.0 specification lays them out; positions,
// colours and indices read back from the binary chunk.
// Georeferenced meshes (a local frame plus its world origin): PLY, OBJ and OFF carry world
// coordinates in double precision; STL and glTF keep float32 local vertices and the origin.
TEST(MeshFormats, WritersPutGeoreferencedMeshesBackInTheWorld) {
  const TriangleMesh m = coloured_tetrahedron();
  const Eigen::Vector3d origin(5000000.25, 4000000.0, 100.0);
  const Eigen::Vector3d first = m.vertices[0].cast<double>() + origin;
  const std::string dir = test::temp_dir();
  write_mesh(dir + "/m.ply", m, origin);
  const std::string ply = test::read_file(dir + "/m.ply");
  EXPECT_NE(ply.find("property double x\nproperty double y\nproperty double z\n"),
            std::string::npos);
  double xyz[3];
  std::memcpy(xyz, ply.data() + ply.find("end_header\n") + 11, sizeof xyz);
  EXPECT_EQ(Eigen::Vector3d(xyz[0], xyz[1], xyz[2]), first);
  for (const char* ext : {".obj", ".off"}) {
    write_mesh(dir + "/m" + ext, m, origin);
    const std::string text = test::read_file(dir + "/m" + ext);
    const std::size_t at =
        std::string(ext) == ".obj" ? text.find("\nv ") + 3 : text.find("\n", text.find(" 0\n")) + 1;
    const char* p = text.c_str() + at;
    char* end = nullptr;
    Eigen::Vector3d w;
    for (int k = 0; k < 3; ++k) {
      w[k] = std::strtod(p, &end);
      p = end;
    }
    EXPECT_LT((w - first).norm(), 1e-4) << ext << ": " << text.substr(at, 60);
  }
  write_mesh(dir + "/m.stl", m, origin);
  EXPECT_LT(test::read_file(dir + "/m.stl").find("origin 5000000.250 4000000.000 100.000"), 80u)
      << "in the 80-byte header";
  expect_same_geometry(m, read_mesh(dir + "/m.stl"));  // the local vertices
  const std::vector<std::uint8_t> glb = encode_glb(m, origin);
  const auto json_length = read_at<std::uint32_t>(glb, 12);
  const nlohmann::json doc =
      nlohmann::json::parse(glb.begin() + 20, glb.begin() + 20 + json_length);
  EXPECT_EQ(doc["nodes"][0]["translation"], (nlohmann::json{5000000.25, 4000000.0, 100.0}));
}

TEST(MeshFormats, GlbFollowsTheGltf2Layout) {
  const TriangleMesh m = coloured_tetrahedron();
  const std::vector<std::uint8_t> glb = encode_glb(m);
  ASSERT_GE(glb.size(), 28u);
  EXPECT_EQ(read_at<std::uint32_t>(glb, 0), 0x46546C67u);
  EXPECT_EQ(read_at<std::uint32_t>(glb, 4), 2u);
  EXPECT_EQ(read_at<std::uint32_t>(glb, 8), glb.size());
  const auto json_length = read_at<std::uint32_t>(glb, 12);
  EXPECT_EQ(json_length % 4, 0u);
  EXPECT_EQ(read_at<std::uint32_t>(glb, 16), 0x4E4F534Au);
  const nlohmann::json doc =
      nlohmann::json::parse(glb.begin() + 20, glb.begin() + 20 + json_length);
  const std::size_t bin_at = 20 + json_length;
  EXPECT_EQ(read_at<std::uint32_t>(glb, bin_at + 4), 0x004E4942u);
  const std::size_t bin = bin_at + 8;
  EXPECT_EQ(doc["asset"]["version"], "2.0");
  const auto& primitive = doc["meshes"][0]["primitives"][0];
  EXPECT_EQ(primitive["mode"], 4);
  const auto accessor = [&](const nlohmann::json& index) {
    return doc["accessors"][index.get<int>()];
  };
  const auto offset = [&](const nlohmann::json& a) {
    return bin + doc["bufferViews"][a["bufferView"].get<int>()]["byteOffset"].get<std::size_t>();
  };
  const nlohmann::json position = accessor(primitive["attributes"]["POSITION"]);
  EXPECT_EQ(position["count"], m.vertices.size());
  EXPECT_EQ(position["min"].size(), 3u);
  for (std::size_t i = 0; i < m.vertices.size(); ++i)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(read_at<float>(glb, offset(position) + 12 * i + 4 * k), m.vertices[i][k]);
  const nlohmann::json color = accessor(primitive["attributes"]["COLOR_0"]);
  EXPECT_TRUE(color["normalized"].get<bool>());
  EXPECT_EQ(glb[offset(color) + 4 * 2 + 0], m.colors[2].r);
  EXPECT_TRUE(primitive["attributes"].contains("NORMAL"));
  const nlohmann::json indices = accessor(primitive["indices"]);
  EXPECT_EQ(indices["count"], 3 * m.triangles.size());
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(read_at<std::uint32_t>(glb, offset(indices) + 12 * t + 4 * c), m.triangles[t][c]);
  EXPECT_THROW(encode_glb(TriangleMesh{}), Error);
}

// A .glb whose JSON points outside its binary chunk, or has an index past the vertices, or is
// no glTF at all: an error naming the file and the field.
TEST(MeshFormats, GlbReaderRefusesBrokenFiles) {
  const std::vector<std::uint8_t> glb = encode_glb(coloured_tetrahedron());
  const auto json_length = read_at<std::uint32_t>(glb, 12);
  nlohmann::json doc = nlohmann::json::parse(glb.begin() + 20, glb.begin() + 20 + json_length);
  const std::vector<unsigned char> bin(glb.begin() + 20 + json_length + 8, glb.end());
  // Rebuilds the file around an edited JSON chunk (padded with spaces as glTF asks).
  const auto rebuild = [&](const nlohmann::json& edited) {
    std::string json = edited.dump();
    json.resize((json.size() + 3) / 4 * 4, ' ');
    std::vector<unsigned char> out;
    const auto u32 = [&](std::uint32_t v) {
      for (int k = 0; k < 4; ++k) out.push_back(static_cast<unsigned char>(v >> (8 * k)));
    };
    u32(0x46546C67u), u32(2), u32(static_cast<std::uint32_t>(28 + json.size() + bin.size()));
    u32(static_cast<std::uint32_t>(json.size())), u32(0x4E4F534Au);
    out.insert(out.end(), json.begin(), json.end());
    u32(static_cast<std::uint32_t>(bin.size())), u32(0x004E4942u);
    out.insert(out.end(), bin.begin(), bin.end());
    return out;
  };
  EXPECT_EQ(decode_glb(rebuild(doc), "same.glb").triangles.size(), 4u);
  nlohmann::json far = doc;
  far["accessors"][0]["count"] = 1000000;
  nlohmann::json index = doc;
  const int indices = doc["meshes"][0]["primitives"][0]["indices"];
  index["accessors"][indices]["componentType"] = 5126;  // float indices
  nlohmann::json lines = doc;
  lines["meshes"][0]["primitives"][0]["mode"] = 1;
  // Numbers nlohmann would cast to integers with undefined behaviour: refused by name.
  nlohmann::json huge = doc;
  huge["accessors"][0]["count"] = 1e30;
  nlohmann::json negative = doc;
  negative["bufferViews"][0]["byteStride"] = -1.5;
  // A primitive repeated 600 times decodes its accessors 600 times: refused past 16x the chunk
  // (and 64 KiB).
  nlohmann::json repeated = doc;
  for (int i = 0; i < 600; ++i)
    repeated["meshes"][0]["primitives"].push_back(doc["meshes"][0]["primitives"][0]);
  const struct {
    std::vector<unsigned char> bytes;
    const char* expected;
  } cases[] = {{rebuild(far), "accessors[0]"},
               {rebuild(index), "indices"},
               {rebuild(lines), "mode"},
               {rebuild(huge), "accessors[0].count"},
               {rebuild(negative), "byteStride"},
               {rebuild(repeated), "16 times"},
               {std::vector<unsigned char>(40, 'x'), "magic"}};
  for (const auto& c : cases) {
    try {
      decode_glb(c.bytes, "bad.glb");
      ADD_FAILURE() << "no error for " << c.expected;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("bad.glb"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.expected), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace meshflow::io
