// Welding chunk meshes apart (nodes/chunk/seam_weld.h, as meshflow-mpi's ranks do): the chunks'
// seam summaries plan the weld, each chunk is welded on its own in any order, and the parts
// concatenated in chunk order are MeshStitcher's mesh of the same chunks, byte for byte.

#include "nodes/chunk/seam_weld.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <map>
#include <set>
#include <vector>

#include "graph/chunked_reconstruction.h"
#include "nodes/chunk/mesh_stitch.h"
#include "nodes/io/ply_point_writer.h"
#include "nodes/synthetic/city_scene.h"
#include "runtime/triangle_mesh.h"
#include "test_support.h"

namespace meshflow {
namespace {

struct WeldChunk {
  TriangleMesh mesh;
  std::vector<std::uint8_t> flags;
};

// The chunk meshes (and their flags) of the synthetic city without normals (estimated and
// oriented per chunk, so some chunks come wound the other way) in chunk order.
std::vector<WeldChunk> city_chunk_meshes(float voxel, float chunk_metres, int& chunk_cells) {
  synthetic::CitySceneConfig scene_config;
  scene_config.size = 90.0f;
  scene_config.block = 30.0f;
  const synthetic::CityScene scene(scene_config);
  const std::string path = test::temp_dir() + "/seam_weld_city.ply";
  {
    io::PlyPointWriter writer(path, 120000, false, false);
    scene.sample(120000, 0.0f, [&](const PointCloud& batch) {
      PointCloud positions;
      positions.positions = batch.positions;
      writer.append(positions);
    });
    writer.finish();
  }
  ReconstructionConfig config;
  config.voxelize.voxel_size = voxel;
  ChunkingConfig chunking;
  chunking.chunk_size = chunk_metres;
  chunking.directory = test::temp_dir();
  std::vector<chunk::ChunkFile> files;
  InputDecisions decided;
  const auto store = partition_input(path, "", config, chunking, files, decided);
  chunk_cells = store->grid().chunk_cells;
  std::vector<WeldChunk> chunks(files.size());
  mesh_chunk_files(files, store->grid(), store->rows(), config, decided, 2,
                   finishes_in_place(config, chunking), path, [&](const FramePtr& frame) {
                     if (!frame->ok()) return;
                     chunks[frame->source_index] = {frame->mesh, chunk_vertex_flags(*frame)};
                   });
  std::filesystem::remove(path);
  return chunks;
}

TEST(SeamWeld, ChunksWeldedApartJoinToTheStitchersMesh) {
  const float voxel = 0.9f;
  int cells = 0;
  const std::vector<WeldChunk> chunks = city_chunk_meshes(voxel, 15.0f, cells);
  ASSERT_GT(chunks.size(), 12u);

  chunk::MeshStitcher stitcher = chunk_stitcher(voxel, cells);
  for (const WeldChunk& c : chunks) stitcher.add(c.mesh, c.flags);
  std::size_t merged = 0, turned = 0;
  std::vector<std::uint8_t> stitched_flags;
  const TriangleMesh stitched = stitcher.stitch(&merged, &stitched_flags, &turned);
  ASSERT_GT(merged, 500u) << "seams cross the surface, so vertices must be welded";

  // Three "ranks" own every third chunk; each summarizes its own, in reverse order.
  std::vector<chunk::ChunkSeams> seams(chunks.size());
  for (int rank = 2; rank >= 0; --rank)
    for (std::size_t c = chunks.size(); c-- > 0;)
      if (static_cast<int>(c % 3) == rank)
        seams[c] =
            chunk::summarize_seams(chunks[c].mesh, chunks[c].flags, voxel, cells, kFeatureFlag);
  // What the ranks exchange: the summaries without the owner's per-vertex pieces.
  std::vector<chunk::ChunkSeams> sent = seams;
  for (chunk::ChunkSeams& s : sent) s.vertex_piece.clear();
  std::vector<const chunk::ChunkSeams*> all;
  for (const chunk::ChunkSeams& s : sent) all.push_back(&s);
  const chunk::WeldPlan plan = chunk::plan_weld(all);
  EXPECT_EQ(plan.merged, merged);
  EXPECT_EQ(plan.turned, turned);

  // Each chunk welded on its own, last first; joined in chunk order.
  std::vector<TriangleMesh> parts(chunks.size());
  std::vector<std::vector<std::uint8_t>> part_flags(chunks.size());
  for (std::size_t c = chunks.size(); c-- > 0;)
    parts[c] =
        chunk::weld_chunk(chunks[c].mesh, chunks[c].flags, seams[c], plan, c, &part_flags[c]);
  TriangleMesh joined;
  std::vector<std::uint8_t> joined_flags;
  for (std::size_t c = 0; c < chunks.size(); ++c) {
    chunk::append_welded(joined, parts[c]);
    joined_flags.insert(joined_flags.end(), part_flags[c].begin(), part_flags[c].end());
  }
  EXPECT_EQ(joined.vertices.size(), plan.vertices);
  EXPECT_EQ(joined.triangles.size(), plan.triangles);
  EXPECT_TRUE(joined.vertices == stitched.vertices);
  EXPECT_TRUE(joined.normals == stitched.normals);
  EXPECT_TRUE(joined.triangles == stitched.triangles);
  EXPECT_EQ(joined_flags, stitched_flags);

  // The weld itself against brute force: every triangle of every chunk, as its corners'
  // positions, is in the joined mesh (turned or not), and no two kept vertices coincide.
  using WeldCorner = std::array<float, 3>;
  std::map<std::array<WeldCorner, 3>, int> expected, got;
  const auto corners = [](const TriangleMesh& m, const Triangle& t) {
    std::array<WeldCorner, 3> k;
    for (int i = 0; i < 3; ++i)
      k[i] = {m.vertices[t[i]].x(), m.vertices[t[i]].y(), m.vertices[t[i]].z()};
    std::sort(k.begin(), k.end());
    return k;
  };
  for (const WeldChunk& c : chunks)
    for (const Triangle& t : c.mesh.triangles) ++expected[corners(c.mesh, t)];
  for (const Triangle& t : joined.triangles) ++got[corners(joined, t)];
  EXPECT_TRUE(expected == got);
  // Feature vertices are never welded (one clamped to its cell's box can sit on another vertex).
  std::set<WeldCorner> features;
  for (const WeldChunk& c : chunks)
    for (std::size_t v = 0; v < c.flags.size(); ++v)
      if (c.flags[v] & kFeatureFlag)
        features.insert({c.mesh.vertices[v].x(), c.mesh.vertices[v].y(), c.mesh.vertices[v].z()});
  std::vector<WeldCorner> positions;
  for (const Eigen::Vector3f& v : joined.vertices)
    if (!features.count({v.x(), v.y(), v.z()})) positions.push_back({v.x(), v.y(), v.z()});
  std::sort(positions.begin(), positions.end());
  EXPECT_EQ(std::adjacent_find(positions.begin(), positions.end()), positions.end())
      << "a seam vertex kept twice";
}

}  // namespace
}  // namespace meshflow
