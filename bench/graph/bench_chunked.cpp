// The out-of-core path on meshflow's synthetic city (2 M points with normals, the density of the
// 20 M-point benchmark in bench/chunked_scaling.sh, 30 m chunks, 0.3 m voxels): the partition
// pass alone, and the whole path (partition, chunks through the graph, stitch, optimize), with 1
// and 2 threads.

#include <cstdio>
#include <filesystem>
#include <string>

#include "bench_support.h"
#include "graph/chunked_reconstruction.h"
#include "nodes/io/ply_point_writer.h"
#include "nodes/synthetic/city_scene.h"
#include "runtime/threads.h"

namespace meshflow::bench {
namespace {

constexpr float kVoxel = 0.3f;

// The city as a PLY file in the temporary directory, written once per process.
const std::string& city_path() {
  static const std::string path = [] {
    synthetic::CitySceneConfig config;
    config.size = 95.0f;  // 2 M points at the 20 M-point city's density
    const synthetic::CityScene city(config);
    const std::string p =
        (std::filesystem::temp_directory_path() / "meshflow_bench_city_2m.ply").string();
    const std::uint64_t points = 2000000;
    io::PlyPointWriter writer(p, points, true, false);
    city.sample(points, 0.0f, [&](const PointCloud& batch) { writer.append(batch); });
    writer.finish();
    return p;
  }();
  return path;
}

ChunkingConfig chunking() {
  ChunkingConfig c;
  c.chunk_size = 30.0f;
  return c;
}

ReconstructionConfig config() {
  ReconstructionConfig c;
  c.voxelize.voxel_size = kVoxel;
  return c;
}

void BM_ChunkPartition(benchmark::State& state) {
  ThreadLimit limit(static_cast<int>(state.range(0)));
  const std::string& path = city_path();
  std::size_t chunks = 0;
  for (auto _ : state) {
    std::vector<chunk::ChunkFile> files;
    InputDecisions decided;
    auto store = partition_input(path, "", config(), chunking(), files, decided);
    chunks = files.size();
  }
  state.counters["points/s"] =
      benchmark::Counter(2e6, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["chunks"] = static_cast<double>(chunks);
}
BENCHMARK(BM_ChunkPartition)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ChunkedReconstruct(benchmark::State& state) {
  ThreadLimit limit(static_cast<int>(state.range(0)));
  const std::string& path = city_path();
  std::size_t triangles = 0;
  for (auto _ : state)
    triangles = reconstruct_chunked(path, "", config(), chunking()).mesh.triangles.size();
  state.counters["points/s"] =
      benchmark::Counter(2e6, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["triangles"] = static_cast<double>(triangles);
}
BENCHMARK(BM_ChunkedReconstruct)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace meshflow::bench
