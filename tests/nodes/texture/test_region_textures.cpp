#include "nodes/texture/region_textures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <sstream>

#include "nodes/io/image_io.h"
#include "nodes/io/textured_obj.h"
#include "nodes/optimize/planar/planar_regions.h"
#include "runtime/error.h"
#include "runtime/half_edge_mesh.h"
#include "test_support.h"

namespace meshflow {
namespace {

const Rgb8 kRed{220, 20, 20}, kBlue{20, 20, 220};

// A 1 m x 1 m sheet at z = 0 (20 x 20 cells) and points on it every 5 mm for x < 0.85: red
// where x < 0.5, blue beyond.
struct ColouredSheet {
  TriangleMesh mesh;
  PointCloud points;
  ColouredSheet() {
    mesh = test::grid_mesh(21);
    for (auto& v : mesh.vertices) v *= 0.05f;
    for (int j = 0; j <= 200; ++j)
      for (int i = 0; i <= 170; ++i) {
        const float x = 0.005f * static_cast<float>(i), y = 0.005f * static_cast<float>(j);
        points.positions.emplace_back(x, y, 0.0f);
        points.colors.push_back(x < 0.5f ? kRed : kBlue);
      }
  }
};

Rgb8 texel(const Image& image, float u, float v) {
  const int column =
      std::min(image.cols() - 1, static_cast<int>(u * static_cast<float>(image.cols())));
  const int row = std::min(image.rows() - 1, static_cast<int>((1.0f - v) * image.rows()));
  return image.at<Rgb8>(row, column);
}

TEST(RegionTextures, TexelsTakeTheColourOfThePointsUnderThem) {
  const ColouredSheet sheet;
  const PlanarSegmentation s = grow_planar_regions(HalfEdgeMesh(sheet.mesh));
  ASSERT_EQ(s.regions.size(), 1u);
  const TexturedMesh t = texture_planar_regions(sheet.mesh, s, sheet.points);
  ASSERT_EQ(t.textures.size(), 1u);
  const Image& image = t.textures[0].image;
  EXPECT_EQ(image.cols(), 100);  // 1 m at 1 cm per texel
  EXPECT_EQ(image.rows(), 100);
  for (std::int32_t id : t.texture_of_face) EXPECT_EQ(id, 0);
  // Texture coordinates follow the plane: find u for x and v for y from two vertices.
  const auto& uv = t.uv;
  auto uv_of = [&](std::uint32_t vertex) {
    for (std::size_t f = 0; f < sheet.mesh.triangles.size(); ++f)
      for (std::size_t k = 0; k < 3; ++k)
        if (sheet.mesh.triangles[f][k] == vertex) return uv[3 * f + k];
    return Eigen::Vector2f(-1, -1);
  };
  const Eigen::Vector2f origin = uv_of(0), x_end = uv_of(20), y_end = uv_of(20 * 21);
  EXPECT_NEAR((x_end - origin).norm(), 1.0f, 1e-3f);
  EXPECT_NEAR((y_end - origin).norm(), 1.0f, 1e-3f);
  auto at = [&](float x, float y) {  // the texel over the sheet point (x, y)
    const Eigen::Vector2f q = origin + x * (x_end - origin) + y * (y_end - origin);
    return texel(image, q.x(), q.y());
  };
  EXPECT_EQ(at(0.25f, 0.5f), (Rgb8{kRed.r, kRed.g, kRed.b}));  // RGB
  EXPECT_EQ(at(0.7f, 0.3f), (Rgb8{kBlue.r, kBlue.g, kBlue.b}));
  EXPECT_EQ(at(0.97f, 0.5f), (Rgb8{128, 128, 128}));  // 12 cm from the nearest point
  // Vertex colours for the untextured fall-back.
  EXPECT_EQ(t.mesh.colors[0], kRed);
  EXPECT_EQ(t.mesh.colors[14], kBlue);  // x = 0.7
}

TEST(RegionTextures, SmallRegionsKeepVertexColoursAndColourlessPointsAreRefused) {
  const ColouredSheet sheet;
  const PlanarSegmentation s = grow_planar_regions(HalfEdgeMesh(sheet.mesh));
  TextureConfig config;
  config.min_region_faces = 1000;  // the sheet has 800
  const TexturedMesh t = texture_planar_regions(sheet.mesh, s, sheet.points, config);
  EXPECT_TRUE(t.textures.empty());
  EXPECT_TRUE(std::all_of(t.texture_of_face.begin(), t.texture_of_face.end(),
                          [](std::int32_t id) { return id == -1; }));
  PointCloud plain;
  plain.positions = sheet.points.positions;
  EXPECT_THROW(texture_planar_regions(sheet.mesh, s, plain), Error);
}

TEST(RegionTextures, ObjMtlAndPngReferToEachOther) {
  const ColouredSheet sheet;
  const PlanarSegmentation s = grow_planar_regions(HalfEdgeMesh(sheet.mesh));
  const TexturedMesh t = texture_planar_regions(sheet.mesh, s, sheet.points);
  const std::string dir = test::temp_dir();
  io::write_textured_obj(dir + "/sheet.obj", t);
  const std::string obj = test::read_file(dir + "/sheet.obj");
  const std::string mtl = test::read_file(dir + "/sheet.mtl");
  EXPECT_NE(obj.find("mtllib sheet.mtl"), std::string::npos);
  EXPECT_NE(obj.find("usemtl region0"), std::string::npos);
  EXPECT_NE(mtl.find("map_Kd sheet_region0.png"), std::string::npos);
  std::size_t vt = 0, faces = 0;
  std::istringstream lines(obj);
  for (std::string line; std::getline(lines, line);) {
    vt += line.rfind("vt ", 0) == 0 ? 1 : 0;
    faces += line.rfind("f ", 0) == 0 ? 1 : 0;
  }
  EXPECT_EQ(faces, sheet.mesh.triangles.size());
  EXPECT_EQ(vt, 3 * faces);
  const Image png = io::read_color_image_file(dir + "/sheet_region0.png");
  ASSERT_FALSE(png.empty());
  EXPECT_EQ(test::max_abs_difference(png, t.textures[0].image), 0.0);  // lossless
}

}  // namespace
}  // namespace meshflow
