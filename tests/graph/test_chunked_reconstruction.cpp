// The out-of-core path (reconstruct --chunk): chunk meshes stitched on the global grid equal the
// single-process mesh, seams are manifold and welded, the result does not depend on the chunks
// in flight or the threads, and the pieces (chunk grid, store, stitcher) keep their contracts.

#include "graph/chunked_reconstruction.h"

#include <gtest/gtest.h>

#include <tbb/global_control.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <utility>

#include "graph/pipeline.h"
#include "graph/tile_levels.h"
#include "nodes/chunk/mesh_stitch.h"
#include "nodes/chunk/mesh_tiles.h"
#include "nodes/io/glb_reader.h"
#include "nodes/io/mesh_writers.h"
#include "nodes/io/ply_point_writer.h"
#include "nodes/io/read_point_cloud.h"
#include "nodes/optimize/cleanup/hole_filling.h"
#include "nodes/search/mesh_distance_index.h"
#include "nodes/search/spatial_index.h"
#include "nodes/synthetic/city_scene.h"
#include "nodes/voxelize/spacing_sample.h"
#include "runtime/error.h"
#include "runtime/tracing.h"
#include "runtime/voxel_key.h"
#include "test_support.h"

namespace meshflow {
namespace {

using Corner = std::array<std::int64_t, 3>;
using TriangleKey = std::array<Corner, 3>;

// Each triangle as its three corners rounded to 10 um, in a canonical rotation.
std::set<TriangleKey> triangle_keys(const TriangleMesh& mesh) {
  std::set<TriangleKey> keys;
  for (const Triangle& t : mesh.triangles) {
    TriangleKey key;
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a)
        key[k][a] = std::llround(static_cast<double>(mesh.vertices[t[k]][a]) * 1e5);
    const auto first = std::min_element(key.begin(), key.end());
    std::rotate(key.begin(), first, key.end());
    keys.insert(key);
  }
  return keys;
}

// Tiles read back one by one: every vertex of a tile used, no triangle in two tiles, and
// together exactly the triangles of the whole mesh.
struct TileUnion {
  std::set<TriangleKey> joined;
  std::size_t keys = 0, triangles = 0;

  void add(const TriangleMesh& tile) {
    std::vector<bool> used(tile.vertices.size(), false);
    for (const Triangle& t : tile.triangles)
      for (std::uint32_t v : t) used[v] = true;
    EXPECT_EQ(std::count(used.begin(), used.end(), false), 0) << "no unused vertex";
    const std::set<TriangleKey> own = triangle_keys(tile);
    keys += own.size();
    triangles += tile.triangles.size();
    joined.insert(own.begin(), own.end());
  }

  void expect_the_mesh(const TriangleMesh& whole) const {
    EXPECT_EQ(triangles, whole.triangles.size());
    EXPECT_EQ(keys, joined.size()) << "no triangle in two tiles";
    EXPECT_EQ(joined, triangle_keys(whole));
  }
};

// DIR/tileset.json is the index as 3D Tiles 1.1: a root turning glTF's y-up back to z-up, per
// tile a chain of REPLACE tiles from the coarsest level to the tile's own file with the index's
// files and geometric errors, each box holding its content (read back, `origin` added, in the
// root's turned frame), the errors never growing down a chain and 0 at its end.
void expect_tileset_as_index(const std::string& dir) {
  const nlohmann::json index = nlohmann::json::parse(std::ifstream(dir + "/tiles.json"));
  const nlohmann::json tileset = nlohmann::json::parse(std::ifstream(dir + "/tileset.json"));
  EXPECT_EQ(tileset["asset"]["version"], "1.1");
  const nlohmann::json& root = tileset["root"];
  EXPECT_EQ(root["transform"],
            nlohmann::json::parse("[1, 0, 0, 0, 0, 0, -1, 0, 0, 1, 0, 0, 0, 0, 0, 1]"));
  const Eigen::Vector3d origin(index["origin"][0].get<double>(), index["origin"][1].get<double>(),
                               index["origin"][2].get<double>());
  ASSERT_EQ(root["children"].size(), index["tiles"].size());
  for (std::size_t t = 0; t < index["tiles"].size(); ++t) {
    const nlohmann::json* node = &root["children"][t];
    double parent_error = root["geometricError"].get<double>();
    for (const nlohmann::json& level : index["tiles"][t]["levels"]) {
      EXPECT_EQ((*node)["refine"], "REPLACE");
      EXPECT_EQ((*node)["content"]["uri"], level["file"]);
      const double error = (*node)["geometricError"].get<double>();
      EXPECT_EQ(error, level["geometric_error"].get<double>());
      EXPECT_LE(error, parent_error);
      parent_error = error;
      const std::vector<double> box = (*node)["boundingVolume"]["box"].get<std::vector<double>>();
      const TriangleMesh m = io::read_glb_mesh(dir + "/" + level["file"].get<std::string>());
      for (const Eigen::Vector3f& v : m.vertices) {
        const Eigen::Vector3d p = v.cast<double>() + origin;
        const Eigen::Vector3d q(p.x(), -p.z(), p.y());  // as 3D Tiles turns glTF
        EXPECT_LE(std::abs(q.x() - box[0]), box[3]);
        EXPECT_LE(std::abs(q.y() - box[1]), box[7]);
        EXPECT_LE(std::abs(q.z() - box[2]), box[11]);
      }
      if (!node->contains("children")) break;
      ASSERT_EQ((*node)["children"].size(), 1u);
      node = &(*node)["children"][0];
    }
    EXPECT_FALSE(node->contains("children")) << "the chain ends at the tile's own file";
    EXPECT_EQ((*node)["geometricError"].get<double>(), 0.0);
  }
}

struct CityInput {
  synthetic::CityScene scene{[] {
    synthetic::CitySceneConfig c;
    c.size = 90.0f;
    c.block = 30.0f;
    return c;
  }()};
  std::string path = test::temp_dir() + "/chunk_city.ply";
  CityInput(std::uint64_t points, bool normals) {
    io::PlyPointWriter writer(path, points, normals, false);
    scene.sample(points, 0.0f, [&](const PointCloud& batch) {
      if (normals) return writer.append(batch);
      PointCloud positions;
      positions.positions = batch.positions;
      writer.append(positions);
    });
    writer.finish();
  }
  ~CityInput() { std::filesystem::remove(path); }
};

ReconstructionConfig raw_config(float voxel) {
  ReconstructionConfig c;
  c.voxelize.voxel_size = voxel;
  c.optimize.steps.clear();  // compare the extracted surfaces themselves
  c.extract.method = ExtractMethod::kMarchingCubes;
  return c;
}

ChunkingConfig chunks_of(float metres) {
  ChunkingConfig c;
  c.chunk_size = metres;
  c.directory = test::temp_dir();
  c.batch_points = 50000;  // several batches: the streaming path
  // Finished once on the stitched mesh: one process's mesh; the tests of finishing per chunk
  // (the default) set it back.
  c.finish_in_place = false;
  return c;
}

TEST(ChunkedReconstruction, EqualsTheSingleProcessMeshWithManifoldWeldedSeams) {
  const CityInput input(150000, true);
  const float voxel = 0.9f;
  const ReconstructionConfig config = raw_config(voxel);
  ReconstructionPipeline whole_pipeline(config, 1);
  auto frame = std::make_shared<Frame>();
  frame->name = input.path;
  frame->load = [&] { return io::read_point_cloud(input.path); };
  whole_pipeline.run_frame(frame);
  ASSERT_TRUE(frame->ok()) << frame->error;
  const TriangleMesh& whole = frame->mesh;

  const ChunkedResult chunked = reconstruct_chunked(input.path, "", config, chunks_of(15.0f));
  const ChunkedReport& r = chunked.report;
  EXPECT_GT(r.chunks, 12u);
  EXPECT_TRUE(r.failed.empty());
  EXPECT_EQ(r.points, 150000u);
  EXPECT_GT(r.seam_vertices, 500u) << "seams cross the surface, so vertices must be welded";

  const std::set<TriangleKey> a = triangle_keys(whole), b = triangle_keys(chunked.mesh);
  std::size_t common = 0;
  for (const TriangleKey& k : a) common += b.count(k);
  EXPECT_EQ(common, a.size()) << "triangles of the single-process mesh missing from the chunks";
  EXPECT_EQ(common, b.size()) << "triangles only the chunks made";
  EXPECT_EQ(chunked.mesh.triangles.size(), whole.triangles.size());

  const EdgeStatistics seams = edge_statistics(chunked.mesh), single = edge_statistics(whole);
  EXPECT_EQ(seams.non_manifold_edges, 0u);
  EXPECT_EQ(seams.inconsistent_edges, 0u);
  EXPECT_EQ(seams.boundary_edges, single.boundary_edges) << "an unwelded seam leaves a border";
  std::vector<Corner> positions;
  for (const Eigen::Vector3f& v : chunked.mesh.vertices)
    positions.push_back(
        {std::llround(v.x() * 1e5), std::llround(v.y() * 1e5), std::llround(v.z() * 1e5)});
  std::sort(positions.begin(), positions.end());
  EXPECT_EQ(std::adjacent_find(positions.begin(), positions.end()), positions.end())
      << "duplicate vertices";

  double sum = 0.0;
  for (const Eigen::Vector3f& v : chunked.mesh.vertices) sum += input.scene.surface_distance(v);
  EXPECT_LT(sum / static_cast<double>(chunked.mesh.vertices.size()), 0.05 * voxel);
}

TEST(ChunkedReconstruction, SameMeshForAnyChunksInFlightAndThreads) {
  const CityInput input(60000, true);
  const ReconstructionConfig config = raw_config(1.2f);
  ChunkingConfig one = chunks_of(20.0f);
  one.in_flight = 1;
  const TriangleMesh serial =
      test::with_threads(1, [&] { return reconstruct_chunked(input.path, "", config, one).mesh; });
  ChunkingConfig three = chunks_of(20.0f);
  three.in_flight = 3;
  const TriangleMesh parallel = test::with_threads(
      2, [&] { return reconstruct_chunked(input.path, "", config, three).mesh; });
  EXPECT_EQ(serial.vertices, parallel.vertices);
  EXPECT_EQ(serial.triangles, parallel.triangles);
  EXPECT_FALSE(serial.empty());
}

TEST(ChunkedReconstruction, EstimatedNormalsAndTheDefaultOptimizeGiveAnAccurateSurface) {
  const CityInput input(120000, false);  // no normals: estimated and oriented per chunk
  ReconstructionConfig config;
  config.voxelize.voxel_size = 0.9f;
  const ChunkedResult chunked = reconstruct_chunked(input.path, "", config, chunks_of(15.0f));
  ASSERT_FALSE(chunked.mesh.empty());
  double sum = 0.0;
  for (const Eigen::Vector3f& v : chunked.mesh.vertices) sum += input.scene.surface_distance(v);
  EXPECT_LT(sum / static_cast<double>(chunked.mesh.vertices.size()), 0.1 * 0.9);
  const EdgeStatistics edges = edge_statistics(chunked.mesh);
  EXPECT_EQ(edges.non_manifold_edges, 0u);
  EXPECT_EQ(edges.inconsistent_edges, 0u) << "chunks oriented on their own must agree at seams";
  // Outward: the faces of roofs and terrain (face normal within 25 degrees of vertical) face up.
  double up = 0.0, down = 0.0;
  for (const Triangle& t : chunked.mesh.triangles) {
    const Eigen::Vector3f& a = chunked.mesh.vertices[t[0]];
    const Eigen::Vector3f n =
        (chunked.mesh.vertices[t[1]] - a).cross(chunked.mesh.vertices[t[2]] - a);
    if (std::abs(n.z()) < 0.9f * n.norm()) continue;
    (n.z() > 0.0f ? up : down) += n.norm();
  }
  EXPECT_GT(up, 99.0 * down) << "the mesh is turned inside out where it faces down";
}

// One process's mesh of `path` with `config`.
TriangleMesh whole_cloud_mesh(const std::string& path, const ReconstructionConfig& config) {
  ReconstructionPipeline pipeline(config, 1);
  auto frame = std::make_shared<Frame>();
  frame->name = path;
  frame->load = [&] { return io::read_point_cloud(path); };
  pipeline.run_frame(frame);
  EXPECT_TRUE(frame->ok()) << frame->error;
  return frame->mesh;
}

// Triangles of `a` missing from `b` plus those of `b` missing from `a`.
std::size_t triangles_not_shared(const TriangleMesh& a, const TriangleMesh& b) {
  const std::set<TriangleKey> ka = triangle_keys(a), kb = triangle_keys(b);
  std::size_t common = 0;
  for (const TriangleKey& k : ka) common += kb.count(k);
  return ka.size() + kb.size() - 2 * common;
}

// The defaults as a new user meets them: no voxel, no method. The voxel and the method
// (extended marching cubes on these exact samples) are decided once from the whole input,
// extended marching cubes' feature vertices are never welded and its edge flips run on the
// stitched mesh, so `--chunk` extracts and trims one process's mesh for 1 and 3 chunks in
// flight (but for 4 triangles on this scene, see below). The default optimize steps then differ
// only where the holes step fills a hole in another order (a quad's other diagonal). Without
// normals in the input each chunk orients its own estimates, which near a few seams moves extended
// marching cubes' vertices: bounded here at 1 % of the triangles.
TEST(ChunkedReconstruction, DefaultsGiveTheSingleProcessMesh) {
  ReconstructionConfig extracted;  // every default but the optimize steps
  extracted.optimize.steps.clear();
  const ReconstructionConfig defaults;
  {
    const CityInput input(90000, true);
    const TriangleMesh whole = whole_cloud_mesh(input.path, extracted);
    ASSERT_FALSE(whole.empty());
    for (const std::size_t in_flight : {std::size_t{1}, std::size_t{3}}) {
      ChunkingConfig chunking = chunks_of(20.0f);
      chunking.in_flight = in_flight;
      const ChunkedResult chunked = reconstruct_chunked(input.path, "", extracted, chunking);
      const ChunkedReport& r = chunked.report;
      EXPECT_GT(r.chunks, 8u);
      EXPECT_TRUE(r.decided.voxel_automatic);
      EXPECT_EQ(r.decided.method, ExtractMethod::kExtendedMarchingCubes) << "exact samples";
      // Exact on the CLI's cities measured (site 60-120 m, 60 000-300 000 points); this scene
      // (30 m blocks, batches of 50 000 points) keeps 4 triangles apart, not yet traced.
      EXPECT_LE(triangles_not_shared(whole, chunked.mesh), 8u) << in_flight << " in flight";
      EXPECT_EQ(chunked.mesh.triangles.size(), whole.triangles.size());
    }
    const TriangleMesh optimized = whole_cloud_mesh(input.path, defaults);
    const ChunkedResult chunked = reconstruct_chunked(input.path, "", defaults, chunks_of(20.0f));
    EXPECT_EQ(chunked.mesh.triangles.size(), optimized.triangles.size());
    EXPECT_LE(triangles_not_shared(optimized, chunked.mesh), 16u) << "a few hole diagonals";
  }
  const CityInput plain(90000, false);
  const TriangleMesh whole = whole_cloud_mesh(plain.path, defaults);
  const ChunkedResult chunked = reconstruct_chunked(plain.path, "", defaults, chunks_of(20.0f));
  EXPECT_LT(triangles_not_shared(whole, chunked.mesh), whole.triangles.size() / 100);
}

// The triangles of `a` that `b` lacks, as their corner keys.
std::vector<TriangleKey> triangles_only_in(const TriangleMesh& a, const TriangleMesh& b) {
  const std::set<TriangleKey> ka = triangle_keys(a), kb = triangle_keys(b);
  std::vector<TriangleKey> only;
  for (const TriangleKey& k : ka)
    if (kb.count(k) == 0) only.push_back(k);
  return only;
}

// Metres from triangle `key`'s nearest corner to the nearest boundary plane of chunks of
// `cells` cells of `voxel` metres (the grid's lattice is at multiples of the voxel).
double seam_distance(const TriangleKey& key, float voxel, int cells) {
  const double edge = static_cast<double>(voxel) * cells;
  double nearest = 1e30;
  for (const Corner& c : key)
    for (const std::int64_t x : c) {
      const double m = static_cast<double>(x) * 1e-5;
      nearest = std::min(nearest, std::abs(m - std::round(m / edge) * edge));
    }
  return nearest;
}

// Chunks finished where they are meshed (rim trim, clean and holes per chunk, seam vertices
// held fixed; only the seams are finished on the stitched mesh) against finishing the stitched
// mesh once (--finish-after-stitch, one process's mesh but for a few triangles): with the
// defaults, on the city with and without input normals, for 1 and 3 chunks in flight, the
// meshes differ only within a few voxels of a seam (what a held seam keeps: a hole through a
// seam vertex left open, a rim not peeled at a seam vertex, flips decided per side), in at most
// 0.5 % of the triangles, and are manifold and consistently wound.
TEST(ChunkedReconstruction, FinishedInPlaceDiffersFromTheStitchedFinishOnlyAtSeams) {
  const ReconstructionConfig defaults;
  for (const bool normals : {true, false}) {
    SCOPED_TRACE(normals ? "input normals" : "estimated normals");
    const CityInput input(90000, normals);
    const ChunkedResult stitched = reconstruct_chunked(input.path, "", defaults, chunks_of(20.0f));
    ASSERT_FALSE(stitched.mesh.empty());
    TriangleMesh first;
    for (const std::size_t in_flight : {std::size_t{1}, std::size_t{3}}) {
      ChunkingConfig chunking = chunks_of(20.0f);
      chunking.in_flight = in_flight;
      chunking.finish_in_place = true;
      const ChunkedResult in_place = reconstruct_chunked(input.path, "", defaults, chunking);
      const ChunkedReport& r = in_place.report;
      ASSERT_TRUE(r.failed.empty());
      EXPECT_GT(r.chunks, 8u);
      std::vector<TriangleKey> differ = triangles_only_in(in_place.mesh, stitched.mesh);
      const std::vector<TriangleKey> missing = triangles_only_in(stitched.mesh, in_place.mesh);
      differ.insert(differ.end(), missing.begin(), missing.end());
      double farthest = 0.0;
      for (const TriangleKey& k : differ)
        farthest = std::max(farthest, seam_distance(k, r.voxel_size, r.chunk_cells));
      std::printf(
          "%s, %zu in flight: %zu of %zu triangles differ, the farthest %.2f voxels from "
          "a seam\n",
          normals ? "normals" : "no normals", in_flight, differ.size(),
          stitched.mesh.triangles.size(), farthest / r.voxel_size);
      EXPECT_LE(differ.size(), stitched.mesh.triangles.size() / 200);
      // A hole left open at a held seam vertex reaches at most half its loop (of at most
      // max_edges edges, each within a voxel's diagonal) away from that vertex.
      const double reach =
          0.5 * static_cast<double>(HoleFillingConfig{}.max_edges) * std::sqrt(2.0);
      EXPECT_LE(farthest, reach * r.voxel_size) << "a difference away from every seam";
      const EdgeStatistics edges = edge_statistics(in_place.mesh);
      EXPECT_EQ(edges.non_manifold_edges, 0u);
      EXPECT_EQ(edges.inconsistent_edges, 0u);
      if (in_flight == 1) {
        first = in_place.mesh;
      } else {
        EXPECT_EQ(first.vertices, in_place.mesh.vertices) << "another mesh for 3 in flight";
        EXPECT_EQ(first.triangles, in_place.mesh.triangles);
      }
    }
  }
}

// The output streamed as the chunks are welded (each chunk's mesh spilled until the weld's
// plan, written at its rows, the seams finished on their neighbourhood and rewritten) is the
// file of the held mesh, byte for byte: extended marching cubes (flips across seams) with input
// normals, and with normals estimated per chunk (pieces turned by the weld), 1 and 3 in flight.
TEST(ChunkedReconstruction, StreamedOutputIsTheHeldMeshsFileByteForByte) {
  const ReconstructionConfig defaults;
  for (const bool normals : {true, false}) {
    SCOPED_TRACE(normals ? "input normals" : "estimated normals");
    const CityInput input(90000, normals);
    ChunkingConfig chunking = chunks_of(20.0f);
    chunking.finish_in_place = true;
    chunking.in_flight = normals ? 1 : 3;
    const ChunkedResult held = reconstruct_chunked(input.path, "", defaults, chunking);
    ASSERT_FALSE(held.mesh.empty());
    if (normals) {
      EXPECT_EQ(held.report.decided.method, ExtractMethod::kExtendedMarchingCubes);
    }
    const std::string held_path = test::temp_dir() + "/chunk_held.ply";
    const std::string streamed_path = test::temp_dir() + "/chunk_streamed.ply";
    io::write_mesh(held_path, held.mesh, held.origin);
    ASSERT_TRUE(streams_output(streamed_path, defaults, chunking));
    const ChunkedResult streamed =
        reconstruct_chunked_to_ply(input.path, "", defaults, chunking, streamed_path);
    EXPECT_TRUE(streamed.mesh.empty()) << "written, not held";
    EXPECT_EQ(streamed.report.output_triangles, held.mesh.triangles.size());
    EXPECT_EQ(streamed.report.output_vertices, held.mesh.vertices.size());
    EXPECT_EQ(streamed.report.seam_vertices, held.report.seam_vertices);
    EXPECT_TRUE(test::read_file(held_path) == test::read_file(streamed_path))
        << "the streamed file differs from the held mesh's";
    std::filesystem::remove(held_path);
    std::filesystem::remove(streamed_path);
  }
}

// The voxel decided from the whole input is one process's automatic voxel, bit for bit, with
// the input read in batches of any size.
TEST(ChunkedReconstruction, DecidesOneProcesssVoxelFromTheStreamedInput) {
  const CityInput input(60000, false);
  const ReconstructionConfig config;
  const PointCloud cloud = io::read_point_cloud(input.path);
  const KdTreeIndex index(cloud.positions);
  const float expected = auto_voxel_size(cloud, index);
  for (const std::size_t batch : {std::size_t{7000}, std::size_t{1} << 20}) {
    const InputDecisions d = decide_from_input(input.path, "", config, batch);
    EXPECT_EQ(d.voxel_size, expected) << "batches of " << batch;
    EXPECT_TRUE(d.voxel_automatic);
  }
  ReconstructionConfig given;
  given.voxelize.voxel_size = 0.7f;
  given.extract.method = ExtractMethod::kMarchingCubes;
  const InputDecisions fixed = decide_from_input(input.path, "", given, 7000);
  EXPECT_EQ(fixed.voxel_size, 0.7f);
  EXPECT_FALSE(fixed.voxel_automatic);
  EXPECT_EQ(fixed.method, ExtractMethod::kMarchingCubes);
  EXPECT_EQ(fixed.median_variation, 0.0f) << "nothing automatic: no pass over the input";
}

// A partition by byte ranges (each range's thread spilling its own part of the chunk files)
// gives every chunk exactly the points a serial stream gives it, in the same order; the
// chunks' own cells hold every point of the whole read once.
TEST(ChunkedReconstruction, PartitionByByteRangesHoldsTheWholeReadsPoints) {
  const CityInput input(50000, true);
  const ReconstructionConfig config = raw_config(1.0f);
  ChunkingConfig serial = chunks_of(15.0f), ranged = chunks_of(15.0f);
  serial.read_parts = 1;
  ranged.read_parts = 3;
  std::vector<chunk::ChunkFile> one, three;
  InputDecisions d1, d3;
  const auto store1 = partition_input(input.path, "", config, serial, one, d1);
  const auto store3 = test::with_threads(
      2, [&] { return partition_input(input.path, "", config, ranged, three, d3); });
  ASSERT_EQ(one.size(), three.size());
  EXPECT_EQ(store3->points_read(), 50000u);
  EXPECT_EQ(store3->rows_written(), store1->rows_written());
  std::size_t split = 0;
  const PointCloud whole = io::read_point_cloud(input.path);
  std::multiset<std::array<float, 3>> owned;
  for (std::size_t i = 0; i < one.size(); ++i) {
    EXPECT_EQ(one[i].index, three[i].index);
    EXPECT_EQ(one[i].points, three[i].points);
    EXPECT_EQ(one[i].core_points, three[i].core_points);
    split += three[i].parts.empty() ? 0 : 1;
    const PointCloud a = store1->read(one[i]), b = store3->read(three[i]);
    EXPECT_EQ(a.positions, b.positions) << "chunk " << i;
    EXPECT_EQ(a.normals, b.normals) << "chunk " << i;
    EXPECT_EQ(b.origin, whole.origin);
    const CellRange range = store3->grid().owned_cells(three[i].index);
    for (const Eigen::Vector3f& p : b.positions) {
      if (range.contains(cell_of(p, d3.voxel_size))) owned.insert({p.x(), p.y(), p.z()});
    }
  }
  EXPECT_GT(split, 0u) << "some chunk's points come from several ranges";
  std::multiset<std::array<float, 3>> expected;
  for (const Eigen::Vector3f& p : whole.positions) expected.insert({p.x(), p.y(), p.z()});
  EXPECT_EQ(owned, expected) << "every point once, in the chunk owning its cell";
}

// The report times every phase of the run in order, the partition's as parallel when the
// input is read by byte ranges (as many as workers) and as serial when one thread streams it
// (a text cloud).
TEST(ChunkedReconstruction, TimesEveryPhaseSerialOnlyWhereOneCoreWorks) {
  const CityInput input(30000, false);
  const std::string text = test::temp_dir() + "/chunk_city.xyz";
  {
    std::ofstream out(text);
    for (const Eigen::Vector3f& p : io::read_point_cloud(input.path).positions)
      out << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  }
  for (const std::string& path : {input.path, text}) {
    const bool streamed = path == text;
    const double t0 = monotonic_seconds();
    const ChunkedResult r = test::with_threads(
        2, [&] { return reconstruct_chunked(path, "", raw_config(1.0f), chunks_of(15.0f)); });
    const double wall = monotonic_seconds() - t0;
    const std::vector<chunk::PhaseTime>& p = r.report.clock.phases();
    const std::vector<std::string> names = {"decide", "partition", "chunks", "stitch", "finish"};
    ASSERT_EQ(p.size(), names.size()) << path;
    double sum = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      EXPECT_EQ(p[i].name, names[i]);
      EXPECT_GE(p[i].wall_s, 0.0);
      EXPECT_FALSE(p[i].waiting);
      sum += p[i].wall_s;
    }
    EXPECT_LE(sum, wall) << "phases do not overlap";
    EXPECT_EQ(p[0].serial, streamed) << path;
    EXPECT_EQ(p[1].serial, streamed) << path;
    EXPECT_FALSE(p[2].serial);
    EXPECT_TRUE(p[3].serial);
    EXPECT_TRUE(p[4].serial);
    EXPECT_GT(p[2].cpu_s, 0.0) << "the chunks were meshed";
    EXPECT_GT(r.mesh.triangles.size(), 1000u) << path;
  }
  std::filesystem::remove(text);
}

// The city of `points` points meshed at `voxel` in chunks of `chunk_edge` m, and its tiles.
struct CityTiles {
  ChunkedResult result;
  chunk::ChunkGrid grid;
  std::vector<chunk::MeshTile> tiles;
};
CityTiles city_tiles(std::uint64_t points, float voxel, float chunk_edge) {
  const CityInput input(points, true);
  CityTiles out;
  out.result = reconstruct_chunked(input.path, "", raw_config(voxel), chunks_of(chunk_edge));
  out.grid = chunk::ChunkGrid{out.result.report.voxel_size, out.result.report.chunk_cells, 0};
  out.tiles = chunk::split_into_tiles(out.result.mesh, out.grid);
  return out;
}

// --tiles: every triangle of the mesh in exactly one tile, the one of the chunk holding its
// centroid; the tiles written as glTF files and an index read back to the whole mesh (issue 61:
// the tiles' union equals the whole mesh).
TEST(MeshTiles, TheTilesUnionIsTheWholeMesh) {
  const auto& [r, grid, tiles] = city_tiles(30000, 1.0f, 15.0f);
  EXPECT_GT(tiles.size(), 4u);
  const std::string dir = test::temp_dir() + "/tiles";
  const Eigen::Vector3d origin(100.5, -200.25, 3.0);
  chunk::write_tiles(dir, tiles, grid, origin);
  std::ifstream index_file(dir + "/tiles.json");
  const nlohmann::json index = nlohmann::json::parse(index_file);
  EXPECT_EQ(index["format"], "meshflow-tiles-2");
  EXPECT_EQ(index["origin"][0].get<double>(), origin.x());
  EXPECT_EQ(index["origin"][1].get<double>(), origin.y());
  EXPECT_EQ(index["voxel"].get<float>(), grid.voxel_size);
  ASSERT_EQ(index["tiles"].size(), tiles.size());
  TileUnion tiles_read;
  for (std::size_t i = 0; i < tiles.size(); ++i) {
    const nlohmann::json& entry = index["tiles"][i];
    EXPECT_EQ(entry["file"], chunk::tile_file_name(tiles[i].chunk));
    // The glb reader does not apply the node's translation: the tile's own coordinates.
    const TriangleMesh m = io::read_glb_mesh(dir + "/" + entry["file"].get<std::string>());
    EXPECT_EQ(entry["triangles"].get<std::size_t>(), m.triangles.size());
    EXPECT_EQ(entry["vertices"].get<std::size_t>(), m.vertices.size());
    for (const Triangle& t : m.triangles) {
      const Eigen::Vector3f c = (m.vertices[t[0]] + m.vertices[t[1]] + m.vertices[t[2]]) / 3.0f;
      EXPECT_EQ(grid.chunk_of_cell(cell_of(c, grid.voxel_size)), tiles[i].chunk);
    }
    tiles_read.add(m);
  }
  tiles_read.expect_the_mesh(r.mesh);
  expect_tileset_as_index(dir);
  std::filesystem::remove_all(dir);
}

// --tiles on the streamed output: each tile is one chunk's finished rows of the file (read
// back, never the whole mesh held), every triangle of the mesh in exactly one tile, each tile's
// vertices all used; the streamed file itself unchanged by writing tiles.
TEST(MeshTiles, TheStreamedTilesAreTheChunksFinishedRowsAndUnionToTheMesh) {
  const ReconstructionConfig defaults;
  const CityInput input(60000, true);
  ChunkingConfig chunking = chunks_of(20.0f);
  chunking.finish_in_place = true;
  ASSERT_TRUE(streams_output("tiles.ply", defaults, chunking));
  const ChunkedResult held = reconstruct_chunked(input.path, "", defaults, chunking);
  ASSERT_FALSE(held.mesh.empty());
  const std::string dir = test::temp_dir() + "/streamed_tiles";
  std::filesystem::remove_all(dir);
  const std::string plain = test::temp_dir() + "/tiles_plain.ply";
  const std::string tiled = test::temp_dir() + "/tiles_tiled.ply";
  reconstruct_chunked_to_ply(input.path, "", defaults, chunking, plain);
  const ChunkedResult r =
      reconstruct_chunked_to_ply(input.path, "", defaults, chunking, tiled, dir);
  EXPECT_TRUE(test::read_file(plain) == test::read_file(tiled)) << "tiles changed the file";
  EXPECT_GT(r.report.tiles, 4u);
  std::ifstream index_file(dir + "/tiles.json");
  const nlohmann::json index = nlohmann::json::parse(index_file);
  ASSERT_EQ(index["tiles"].size(), r.report.tiles);
  TileUnion tiles_read;
  for (const nlohmann::json& entry : index["tiles"]) {
    const TriangleMesh m = io::read_glb_mesh(dir + "/" + entry["file"].get<std::string>());
    EXPECT_EQ(entry["triangles"].get<std::size_t>(), m.triangles.size());
    EXPECT_EQ(m.normals.size(), m.vertices.size());
    tiles_read.add(m);
  }
  tiles_read.expect_the_mesh(held.mesh);
  std::filesystem::remove_all(dir);
  std::filesystem::remove(plain);
  std::filesystem::remove(tiled);
}

// A position's bits (positions equal bit for bit join).
using PositionBits = std::array<std::uint32_t, 3>;
PositionBits bits_of(const Eigen::Vector3f& p) {
  PositionBits b;
  std::memcpy(b.data(), p.data(), sizeof b);
  return b;
}

// The border of the union of `meshes`, their vertices joined where their positions are equal
// bit for bit: the undirected edges of exactly one of their triangles (a triangle repeating a
// corner counts none), each as its two ends' positions.
std::set<std::pair<PositionBits, PositionBits>> union_border(
    const std::vector<const TriangleMesh*>& meshes) {
  std::map<std::pair<PositionBits, PositionBits>, int> uses;
  for (const TriangleMesh* m : meshes)
    for (const Triangle& t : m->triangles) {
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
      for (int k = 0; k < 3; ++k)
        ++uses[std::minmax(bits_of(m->vertices[t[k]]), bits_of(m->vertices[t[(k + 1) % 3]]))];
    }
  std::set<std::pair<PositionBits, PositionBits>> border;
  for (const auto& [edge, count] : uses)
    if (count == 1) border.insert(edge);
  return border;
}

// Tile levels with locked borders (issue 61): every coarser level of every tile has the tile's
// border edges exactly (their ends bit for bit the tile's, so the neighbour's), and the union of
// any choice of levels (all tiles at the same depth, and coarsest / full in a checkerboard
// and its inverse) has border edges exactly where the whole mesh has them: no crack. Without
// locking, some tile's coarse level leaves its border (the crack the lock removes).
TEST(MeshTiles, LockedBordersLetAnyLevelsOfNeighbouringTilesMeetWithoutCracks) {
  const CityTiles city = city_tiles(60000, 0.5f, 45.0f);
  const std::vector<chunk::MeshTile>& tiles = city.tiles;  // (a lambda below captures it)
  ASSERT_GE(tiles.size(), 4u);
  std::vector<std::vector<TriangleMesh>> levels;  // per tile: coarse to fine, the tile last
  std::size_t coarse = 0, deep = 0;
  bool unlocked_left_a_border = false;
  TileLevelConfig unlocked;
  unlocked.lock_border = false;
  for (const chunk::MeshTile& tile : tiles) {
    levels.push_back(progressive_tile_levels(tile.mesh));
    coarse += levels.back().size();
    deep += levels.back().size() >= 2 ? 1 : 0;
    const auto own = union_border({&tile.mesh});
    for (const TriangleMesh& level : levels.back())
      EXPECT_EQ(union_border({&level}), own) << tile.chunk.transpose();
    const std::vector<TriangleMesh> free = progressive_tile_levels(tile.mesh, unlocked);
    if (!free.empty() && union_border({&free.front()}) != own) unlocked_left_a_border = true;
    levels.back().push_back(tile.mesh);
  }
  // (17 tiles, some small corners of a chunk: 11 coarser levels, 5 tiles with two or three.)
  EXPECT_GE(coarse, 10u);
  EXPECT_GE(deep, 4u) << "tiles with two coarser levels or more";
  EXPECT_TRUE(unlocked_left_a_border);
  const auto whole = union_border({&city.result.mesh});
  ASSERT_FALSE(whole.empty()) << "the city's mesh has borders of its own";
  const auto choose = [&](const auto& pick) {
    std::vector<const TriangleMesh*> chosen;
    for (std::size_t i = 0; i < tiles.size(); ++i)
      chosen.push_back(&levels[i][std::min(pick(i), levels[i].size() - 1)]);
    return union_border(chosen);
  };
  for (std::size_t depth = 0; depth <= 3; ++depth)
    EXPECT_EQ(choose([&](std::size_t) { return depth; }), whole) << "every tile at " << depth;
  for (std::size_t parity : {0, 1}) {
    const auto checker = [&](std::size_t i) -> std::size_t {
      const Eigen::Vector3i& c = tiles[i].chunk;
      return static_cast<std::size_t>(c.x() + c.y() + c.z() + 64) % 2 == parity ? 0 : 3;
    };
    EXPECT_EQ(choose(checker), whole) << "checkerboard " << parity;
  }
  std::printf("%zu tiles, %zu coarser levels (%zu tiles with two or more)\n", tiles.size(), coarse,
              deep);
}

// A grid of n x n squares (two triangles each) of edge `step` over the x-y plane at height
// z(x, y).
template <typename Height>
TriangleMesh height_field(int n, float step, Height z) {
  TriangleMesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.vertices.emplace_back(i * step, j * step, z(i * step, j * step));
  const auto at = [n](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      m.triangles.push_back(Triangle{at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      m.triangles.push_back(Triangle{at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return m;
}

// level_error() against analytic distances: a mesh is 0 from itself; a flat grid is `d` from
// the same grid lifted by d, and from a coarser grid of the same plane lifted by d.
TEST(MeshTiles, LevelErrorIsTheDistanceBetweenTheSurfaces) {
  const auto flat = [](float, float) { return 0.0f; };
  const TriangleMesh fine = height_field(16, 0.5f, flat);
  EXPECT_EQ(chunk::level_error(fine, fine), 0.0);
  const TriangleMesh lifted = height_field(16, 0.5f, [](float, float) { return 0.25f; });
  EXPECT_NEAR(chunk::level_error(fine, lifted), 0.25, 1e-6);
  const TriangleMesh coarse = height_field(4, 2.0f, [](float, float) { return -0.125f; });
  EXPECT_NEAR(chunk::level_error(fine, coarse), 0.125, 1e-6);
  // A bump the coarse grid misses: the fine vertex at its top is 1 from the coarse plane.
  const TriangleMesh bump =
      height_field(16, 0.5f, [](float x, float y) { return x == 3.5f && y == 4.5f ? 1.0f : 0.0f; });
  EXPECT_NEAR(chunk::level_error(bump, height_field(4, 2.0f, flat)), 1.0, 1e-6);
  EXPECT_TRUE(std::isinf(chunk::level_error(fine, TriangleMesh{})));
}

// The progressive coder's levels of a smooth surface: at most `levels` of them, coarse to fine,
// each of fewer triangles than the next and than the tile, near the tile's triangles / 4^k, the
// coarser the farther from the tile (the coder rounds a tile's corners off: the error is the
// fine corner's distance to the coarse border, most at the coarsest level), their vertices on
// the tile within the coder's quantisation (half a step of 1/64 of the median edge, per axis);
// a small tile gets none.
TEST(MeshTiles, ProgressiveLevelsAreCoarseToFineApproximationsOfTheTile) {
  const TriangleMesh tile = height_field(
      96, 0.25f, [](float x, float y) { return 2.0f * std::sin(x * 0.3f) * std::cos(y * 0.25f); });
  const std::size_t t = tile.triangles.size();
  float max_edge = 0.0f;
  for (const Triangle& f : tile.triangles)
    for (int k = 0; k < 3; ++k)
      max_edge = std::max(max_edge, (tile.vertices[f[k]] - tile.vertices[f[(k + 1) % 3]]).norm());
  const std::vector<TriangleMesh> levels = progressive_tile_levels(tile);
  ASSERT_EQ(levels.size(), 3u);
  std::vector<double> errors;
  for (std::size_t k = 0; k < levels.size(); ++k) {
    const std::size_t n = levels[k].triangles.size();
    const std::size_t finer = k + 1 < levels.size() ? levels[k + 1].triangles.size() : t;
    EXPECT_LT(n, finer);
    EXPECT_GE(static_cast<double>(n), static_cast<double>(t) / std::pow(4.0, 3 - k) * 0.9) << k;
    EXPECT_LE(static_cast<double>(n), static_cast<double>(t) / std::pow(4.0, 3 - k) * 1.5) << k;
    errors.push_back(chunk::level_error(tile, levels[k]));
    const MeshDistanceIndex on_tile(tile);
    for (const Eigen::Vector3f& v : levels[k].vertices)
      EXPECT_LE(on_tile.closest(v).distance, std::sqrt(3.0f) * max_edge / 128.0f) << k;
  }
  EXPECT_GT(errors[0], errors[1]);
  EXPECT_GT(errors[1], errors[2]);
  EXPECT_GT(errors[2], 0.0);
  EXPECT_LT(errors[2], errors[0] / 4.0) << "finer levels converge on the tile";
  EXPECT_LT(errors[0], 24.0f / 4.0f) << "a quarter of the tile's side";
  EXPECT_TRUE(
      progressive_tile_levels(height_field(8, 1.0f, [](float, float) { return 0.0f; })).empty());
}

// --tiles with levels (issue 61): every level of every tile decodes, the levels go coarse to
// fine with growing triangles and errors that never grow, the finest is the tile's own file
// (which the union tests cover), and the index's triangles, bytes and geometric errors are
// those of the files (the errors recomputed from the files read back); tileset.json says the
// same as 3D Tiles. The files are the same at one thread and at all.
TEST(MeshTiles, EveryLevelOfEveryTileDecodesAndTheIndexMatchesTheFiles) {
  const CityInput input(60000, true);
  ChunkingConfig chunking = chunks_of(20.0f);
  chunking.finish_in_place = true;
  const std::string dir = test::temp_dir() + "/level_tiles";
  const std::string output = test::temp_dir() + "/level_tiles.ply";
  std::filesystem::remove_all(dir);
  const ChunkedResult r =
      reconstruct_chunked_to_ply(input.path, "", ReconstructionConfig{}, chunking, output, dir);
  std::ifstream index_file(dir + "/tiles.json");
  const nlohmann::json index = nlohmann::json::parse(index_file);
  EXPECT_EQ(index["format"], "meshflow-tiles-2");
  ASSERT_EQ(index["tiles"].size(), r.report.tiles);
  std::size_t with_levels = 0, files = 2;  // tiles.json, tileset.json
  for (const nlohmann::json& entry : index["tiles"]) {
    const nlohmann::json& levels = entry["levels"];
    ASSERT_GE(levels.size(), 1u);
    files += levels.size();
    with_levels += levels.size() > 1 ? 1 : 0;
    const nlohmann::json& finest = levels.back();
    EXPECT_EQ(finest["file"], entry["file"]);
    EXPECT_EQ(finest["triangles"], entry["triangles"]);
    EXPECT_EQ(finest["geometric_error"].get<double>(), 0.0);
    const TriangleMesh tile = io::read_glb_mesh(dir + "/" + entry["file"].get<std::string>());
    double finer_error = 0.0;
    std::size_t finer_triangles = std::numeric_limits<std::size_t>::max();
    for (std::size_t k = levels.size(); k-- > 0;) {
      const nlohmann::json& level = levels[k];
      const std::string path = dir + "/" + level["file"].get<std::string>();
      const TriangleMesh m = io::read_glb_mesh(path);
      EXPECT_EQ(level["triangles"].get<std::size_t>(), m.triangles.size());
      EXPECT_EQ(level["bytes"].get<std::uintmax_t>(), std::filesystem::file_size(path));
      EXPECT_LT(m.triangles.size(), finer_triangles) << "coarse to fine";
      const double error = level["geometric_error"].get<double>();
      EXPECT_GE(error, finer_error) << "errors never grow from coarse to fine";
      finer_error = std::max(finer_error, chunk::level_error(tile, m));
      EXPECT_EQ(static_cast<float>(error), static_cast<float>(finer_error)) << path;
      if (k + 1 < levels.size()) {
        EXPECT_GT(error, 0.0);
      }
      finer_triangles = m.triangles.size();
    }
  }
  EXPECT_GT(with_levels, r.report.tiles / 2) << "most city tiles get coarser levels";
  EXPECT_EQ(static_cast<std::size_t>(std::distance(std::filesystem::directory_iterator(dir),
                                                   std::filesystem::directory_iterator())),
            files)
      << "every file listed once";
  expect_tileset_as_index(dir);
  // The same files at one thread.
  const std::string one = test::temp_dir() + "/level_tiles_1";
  std::filesystem::remove_all(one);
  {
    const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 1);
    reconstruct_chunked_to_ply(input.path, "", ReconstructionConfig{}, chunking, output, one);
  }
  for (const auto& file : std::filesystem::directory_iterator(dir))
    EXPECT_TRUE(test::read_file(file.path().string()) ==
                test::read_file(one + "/" + file.path().filename().string()))
        << file.path();
  std::filesystem::remove_all(dir);
  std::filesystem::remove_all(one);
  std::filesystem::remove(output);
}

TEST(MeshStitch, TurnsAChunkWoundAgainstItsNeighbourOver) {
  // A 2 x 2 grid of unit cells at height 0.5 (vertices on vertical lattice edges), split at the
  // chunk plane x = 1 (chunk edge 1 cell); the right chunk arrives wound the other way.
  const float v = 1.0f;
  const auto quad = [](float x0) {
    TriangleMesh m;
    m.vertices = {{x0, 0, 0.5f}, {x0 + 1, 0, 0.5f}, {x0 + 1, 1, 0.5f}, {x0, 1, 0.5f}};
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    return m;
  };
  TriangleMesh left = quad(0.0f), right = quad(1.0f), third = quad(2.0f);
  for (Triangle& t : right.triangles) std::swap(t[1], t[2]);
  chunk::MeshStitcher stitcher(v, 1);
  stitcher.add(left);
  stitcher.add(right);
  stitcher.add(third);
  std::size_t turned = 0;
  const TriangleMesh joined = stitcher.stitch(nullptr, nullptr, &turned);
  EXPECT_EQ(turned, 2u);
  EXPECT_EQ(edge_statistics(joined).inconsistent_edges, 0u);
  for (const Triangle& t : joined.triangles) {  // the majority (left, third) faces up: +z
    const Eigen::Vector3f n = (joined.vertices[t[1]] - joined.vertices[t[0]])
                                  .cross(joined.vertices[t[2]] - joined.vertices[t[0]]);
    EXPECT_GT(n.z(), 0.0f);
  }
  chunk::MeshStitcher minority(v, 1);  // now the turned chunks are the majority: all face down
  for (Triangle& t : left.triangles) std::swap(t[1], t[2]);
  for (Triangle& t : third.triangles) std::swap(t[1], t[2]);
  for (Triangle& t : right.triangles) std::swap(t[1], t[2]);
  minority.add(right);  // up, first
  minority.add(left);   // down
  minority.add(third);  // down
  const TriangleMesh flipped = minority.stitch();
  EXPECT_EQ(edge_statistics(flipped).inconsistent_edges, 0u);
  for (const Triangle& t : flipped.triangles) {
    const Eigen::Vector3f n = (flipped.vertices[t[1]] - flipped.vertices[t[0]])
                                  .cross(flipped.vertices[t[2]] - flipped.vertices[t[0]]);
    EXPECT_LT(n.z(), 0.0f);
  }
}

TEST(ChunkedReconstruction, AutomaticChunkSizeKeepsChunksNearTheMemoryBudget) {
  const std::uint64_t points = 120000;
  const CityInput input(points, true);
  const float voxel = 0.9f;
  const ReconstructionConfig config = raw_config(voxel);
  ChunkingConfig automatic = chunks_of(0.0f);
  // The whole input's density (the scene's points over its surface; the file is written patch
  // by patch, so no first batch sees it), as the partition measures it.
  const InputDecisions decided =
      decide_from_input(input.path, "", config, automatic.batch_points, {}, true);
  const double truth = static_cast<double>(points) / input.scene.area();
  EXPECT_NEAR(decided.density, truth, 0.25 * truth);
  const double edge = 12.0;  // metres: the budget of chunks of this edge by the model
  const int overlap = automatic.overlap_voxels;
  automatic.memory_budget = static_cast<std::size_t>(
      static_cast<double>(automatic.in_flight) * chunk_bytes_estimate(edge, truth, voxel, overlap));
  const ChunkedResult chunked = reconstruct_chunked(input.path, "", config, automatic);
  const ChunkedReport& r = chunked.report;
  EXPECT_NEAR(r.chunk_cells * voxel, edge, 0.2 * edge);
  EXPECT_GT(r.chunks, 6u);
  const double seen = edge + 2.0 * overlap * voxel;  // the model's points per chunk
  const double expected = truth * 2.0 * seen * seen;
  EXPECT_LT(static_cast<double>(r.max_chunk_points), 4.0 * expected) << "far over the budget";
  EXPECT_GT(static_cast<double>(r.max_chunk_points), expected / 4.0) << "far under the budget";
  EXPECT_FALSE(chunked.mesh.empty());
  // A given voxel and method take the sample for the density alone.
  EXPECT_EQ(decide_from_input(input.path, "", config, automatic.batch_points).density, 0.0f);
}

TEST(ChunkGrid, OwnedRangesTileSpaceAndOverlapReachesNeighbours) {
  chunk::ChunkGrid grid{0.1f, 10, 2};
  EXPECT_EQ(grid.chunk_of_cell({-1, 0, 9}), Eigen::Vector3i(-1, 0, 0));
  EXPECT_EQ(grid.chunk_of_cell({-10, -11, 10}), Eigen::Vector3i(-1, -2, 1));
  const CellRange r = grid.owned_cells({-1, 0, 2});
  EXPECT_EQ(r.lo, Eigen::Vector3i(-10, 0, 20));
  EXPECT_EQ(r.hi, Eigen::Vector3i(0, 10, 30));
  std::vector<Eigen::Vector3i> seeing;
  grid.chunks_seeing_cell({5, 5, 5}, seeing);
  EXPECT_EQ(seeing.size(), 1u);
  grid.chunks_seeing_cell({1, 5, 9}, seeing);  // near x = 0 and z = 10
  EXPECT_EQ(seeing.size(), 4u);
  EXPECT_LT(chunk::morton_code({0, 0, 0}), chunk::morton_code({1, 1, 1}));
}

TEST(MeshStitch, LatticeEdgeKeysIdentifyEdgeVerticesOnly) {
  const float v = 0.25f;
  const std::uint64_t k = chunk::lattice_edge_key({0.25f * 3 + 0.1f, 0.5f, -0.75f}, v);
  EXPECT_NE(k, UINT64_MAX);
  EXPECT_EQ(k % 3, 0u);  // along x
  EXPECT_EQ(k, chunk::lattice_edge_key({0.25f * 3 + 0.2f, 0.5f, -0.75f}, v)) << "same edge";
  EXPECT_NE(k, chunk::lattice_edge_key({0.25f * 4 + 0.1f, 0.5f, -0.75f}, v)) << "next edge";
  EXPECT_EQ(chunk::lattice_edge_key({0.1f, 0.13f, 0.5f}, v), UINT64_MAX) << "inside a face";
  EXPECT_EQ(chunk::lattice_edge_key({0.5f, 0.25f, 0.5f}, v), UINT64_MAX) << "a corner";
}

TEST(MeshStitch, WeldsSharedEdgeVerticesAndKeepsTheRest) {
  // Two triangles in neighbouring chunks sharing the vertices on two lattice edges.
  const float v = 1.0f;
  TriangleMesh left, right;
  left.vertices = {{0.5f, 0, 0}, {1, 0.5f, 0}, {0.2f, 0.3f, 0.4f}};  // the last on no edge
  left.triangles = {{0, 1, 2}};
  right.vertices = {{1, 0.5f, 0}, {0.5f, 0, 0}, {1.5f, 1, 0}};
  right.triangles = {{1, 0, 2}};
  chunk::MeshStitcher stitcher(v);
  stitcher.add(left);
  stitcher.add(right);
  std::size_t merged = 0;
  const TriangleMesh joined = stitcher.stitch(&merged);
  EXPECT_EQ(merged, 2u);
  EXPECT_EQ(joined.vertices.size(), 4u);
  ASSERT_EQ(joined.triangles.size(), 2u);
  EXPECT_EQ(joined.triangles[1][0], joined.triangles[0][0]);
  EXPECT_EQ(joined.triangles[1][1], joined.triangles[0][1]);
}

TEST(ChunkStore, EveryPointReachesItsChunkAndTheOverlapOnce) {
  chunk::ChunkGrid grid{1.0f, 4, 1};
  chunk::ChunkStore store(grid, test::temp_dir());
  PointCloud batch;
  batch.positions = {{0.5f, 0.5f, 0.5f},  // chunk 0 only
                     {3.5f, 0.5f, 0.5f},  // cell 3: chunk 0, and chunk 1's overlap
                     {std::nanf(""), 0, 0},
                     {-0.5f, 0.5f, 0.5f}};  // chunk -1, and chunk 0's overlap
  store.add(batch);
  const std::vector<chunk::ChunkFile> files = store.finish();
  EXPECT_EQ(store.points_read(), 3u);
  EXPECT_EQ(store.points_dropped(), 1u);
  std::map<int, chunk::ChunkFile> by_x;
  for (const chunk::ChunkFile& f : files) by_x[f.index.x()] = f;
  ASSERT_EQ(by_x.count(0), 1u);
  EXPECT_EQ(by_x[0].points, 3u);
  EXPECT_EQ(store.read(by_x[0]).positions[1], batch.positions[1]);
  ASSERT_EQ(by_x.count(1), 1u);
  EXPECT_EQ(by_x[1].points, 1u);
  const std::string directory = store.directory();
  EXPECT_TRUE(std::filesystem::exists(directory));
}

TEST(ChunkStore, RemovesItsDirectoryAndRejectsInconsistentBatches) {
  std::string directory;
  {
    chunk::ChunkStore store(chunk::ChunkGrid{1.0f, 4, 1}, test::temp_dir());
    directory = store.directory();
    PointCloud a;
    a.positions = {{0, 0, 0}};
    store.add(a);
    PointCloud b = a;
    b.normals = {{0, 0, 1}};
    EXPECT_THROW(store.add(b), Error);
  }
  EXPECT_FALSE(std::filesystem::exists(directory));
}

TEST(ChunkedReconstruction, BadInputNamesTheFile) {
  const std::string path = test::temp_dir() + "/chunk_truncated.ply";
  test::write_file(path,
                   "ply\nformat binary_little_endian 1.0\nelement vertex 100\n"
                   "property float x\nproperty float y\nproperty float z\nend_header\n");
  try {
    reconstruct_chunked(path, "", ReconstructionConfig{}, chunks_of(5.0f));
    FAIL() << "a truncated file must be an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  ChunkingConfig zero = chunks_of(0.0f);
  EXPECT_THROW(make_chunk_grid(0.1f, zero), Error);
}

}  // namespace
}  // namespace meshflow
