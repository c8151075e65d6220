// PlyMeshFile: a mesh written part by part, in any order, with rows rewritten afterwards, is
// write_ply()'s file of the final mesh byte for byte; an incomplete file never appears.

#include "nodes/io/ply_mesh_file.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "nodes/io/mesh_writers.h"
#include "runtime/error.h"
#include "test_support.h"

namespace meshflow::io {
namespace {

// A strip of `n` triangles with normals and colours.
TriangleMesh ply_strip(std::uint32_t n) {
  TriangleMesh m;
  for (std::uint32_t i = 0; i < n + 2; ++i) {
    m.vertices.emplace_back(0.5f * static_cast<float>(i), static_cast<float>(i % 2), 0.25f);
    m.colors.push_back(Rgb8{static_cast<std::uint8_t>(i), 7, static_cast<std::uint8_t>(3 * i)});
  }
  for (std::uint32_t i = 0; i < n; ++i)
    m.triangles.push_back(i % 2 ? Triangle{i, i + 2, i + 1} : Triangle{i, i + 1, i + 2});
  compute_vertex_normals(m);
  return m;
}

// Rows [first, first + count) of `m` as a mesh of their own (vertices, normals, colours).
TriangleMesh ply_rows(const TriangleMesh& m, std::size_t first, std::size_t count) {
  TriangleMesh part;
  const auto at = [&](const auto& v) {
    return std::vector<typename std::decay_t<decltype(v)>::value_type>(
        v.begin() + static_cast<long>(first), v.begin() + static_cast<long>(first + count));
  };
  part.vertices = at(m.vertices);
  part.normals = at(m.normals);
  part.colors = at(m.colors);
  return part;
}

TEST(PlyMeshFile, PartsInAnyOrderAndRewrittenRowsGiveWritePlysBytes) {
  const std::string dir = test::temp_dir();
  for (const Eigen::Vector3d& origin : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(5e5, 4e6, 12)}) {
    TriangleMesh final_mesh = ply_strip(9);
    write_ply(dir + "/whole.ply", final_mesh, PlyEncoding::kBinary, origin);
    // Written from an earlier state: two triangles and a normal differ until rewritten.
    TriangleMesh early = final_mesh;
    std::swap(early.triangles[3][1], early.triangles[3][2]);
    early.triangles[7] = Triangle{0, 0, 0};
    early.normals[4] = Eigen::Vector3f(1, 0, 0);
    {
      PlyMeshFile file(dir + "/parts.ply", ply_mesh_layout(final_mesh, origin),
                       final_mesh.vertices.size(), final_mesh.triangles.size(), origin);
      file.write_vertices(6, ply_rows(early, 6, 5));  // the second part first
      file.write_vertices(0, ply_rows(early, 0, 6));
      file.write_triangles(4, {early.triangles.begin() + 4, early.triangles.end()});
      file.write_triangles(0, {early.triangles.begin(), early.triangles.begin() + 4});
      file.write_triangle(3, final_mesh.triangles[3]);
      file.write_triangle(7, final_mesh.triangles[7]);
      file.write_normal(4, final_mesh.normals[4]);
      file.commit();
    }
    EXPECT_EQ(test::read_file(dir + "/parts.ply"), test::read_file(dir + "/whole.ply"))
        << "origin " << origin.transpose();
  }
}

TEST(PlyMeshFile, AnIncompleteFileIsAnErrorAndLeavesNothing) {
  const std::string path = test::temp_dir() + "/incomplete.ply";
  std::filesystem::remove(path);
  const TriangleMesh m = ply_strip(4);
  {
    PlyMeshFile file(path, ply_mesh_layout(m, Eigen::Vector3d::Zero()), m.vertices.size(),
                     m.triangles.size(), Eigen::Vector3d::Zero());
    file.write_vertices(0, m);
    EXPECT_THROW(file.write_vertices(1, m), Error) << "past the declared rows";
    EXPECT_THROW(file.commit(), Error) << "no face written";
  }
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
}

// meshflow-mpi's ranks: joined writers fill their rows of the creator's temporary file; the
// creator counts their rows, and the file appears only at its commit, as write_ply()'s.
TEST(PlyMeshFile, JoinedWritersFillTheirRowsAndOnlyTheCreatorCommits) {
  const std::string dir = test::temp_dir();
  const Eigen::Vector3d origin(5e5, 4e6, 12);
  const TriangleMesh m = ply_strip(9);
  write_ply(dir + "/whole.ply", m, PlyEncoding::kBinary, origin);
  const std::string path = dir + "/joined.ply";
  std::filesystem::remove(path);
  const PlyMeshLayout layout = ply_mesh_layout(m, origin);
  {
    PlyMeshFile creator(path, layout, m.vertices.size(), m.triangles.size(), origin);
    creator.write_vertices(0, ply_rows(m, 0, 6));
    creator.write_triangles(0, {m.triangles.begin(), m.triangles.begin() + 4});
    {
      PlyMeshFile joined(path, layout, m.vertices.size(), m.triangles.size(), origin,
                         PlyMeshFile::Role::kJoin);
      joined.write_vertices(6, ply_rows(m, 6, 5));
      joined.write_triangles(4, {m.triangles.begin() + 4, m.triangles.end()});
      EXPECT_THROW(joined.commit(), Error) << "only the creator commits";
      joined.close();
    }
    EXPECT_TRUE(std::filesystem::exists(path + ".tmp")) << "a joined writer removes nothing";
    EXPECT_FALSE(std::filesystem::exists(path));
    EXPECT_THROW(creator.close(), Error) << "the creator commits";
    EXPECT_EQ(creator.vertex_rows_written(), 6u);
    creator.add_rows_written_elsewhere(5, m.triangles.size() - 4);
    creator.commit();
  }
  EXPECT_EQ(test::read_file(path), test::read_file(dir + "/whole.ply"));
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
}

}  // namespace
}  // namespace meshflow::io
