#include <filesystem>

#include "bench_support.h"
#include "nodes/io/mesh_writers.h"
#include "nodes/io/ply_reader.h"
#include "nodes/io/scan3d_reader.h"

namespace meshflow::bench {
namespace {

void BM_Read3dtkScan(benchmark::State& state) {
  if (require(state, kKurt3d) == nullptr) return;
  std::size_t points = 0;
  for (auto _ : state) points = io::read_3dtk_scan(kurt3d_path()).size();
  state.counters["points/s"] = benchmark::Counter(static_cast<double>(points),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Read3dtkScan)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_PlyBinaryRoundTrip(benchmark::State& state) {
  const PointCloud* cloud = input_cloud(kSynthetic);
  TriangleMesh mesh;
  mesh.vertices = cloud->positions;
  const std::string path = (std::filesystem::temp_directory_path() / "meshflow_bench.ply").string();
  for (auto _ : state) {
    io::write_ply(path, mesh);
    benchmark::DoNotOptimize(io::read_ply(path).size());
  }
  std::filesystem::remove(path);
  state.counters["points/s"] = benchmark::Counter(static_cast<double>(cloud->size()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_PlyBinaryRoundTrip)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace meshflow::bench
