#include <filesystem>

#include "bench_support.h"
#include "nodes/io/mesh_writers.h"
#include "nodes/io/ply_reader.h"
#include "nodes/io/read_point_cloud.h"
#include "nodes/io/scan3d_reader.h"
#include "nodes/io/sequence.h"

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

// PCD files of the real data (parse, decompress, coordinate checks): arg 0 = the organized
// Kinect frame kinect_pcl/office1.pcd (binary_compressed, 640 x 480 with colour), 1 = the
// stereo mug (binary_compressed, 640 x 480), 2 = objects/bunny.pcd (ASCII, 397 points).
void BM_ReadPcd(benchmark::State& state) {
  const char* files[] = {"kinect_pcl/office1.pcd", "kinect_pcl/table_scene_mug_stereo_textured.pcd",
                         "objects/bunny.pcd"};
  const std::string path = data_dir() + "/" + files[state.range(0)];
  if (!std::filesystem::exists(path)) {
    state.SkipWithError((path + " not found").c_str());
    return;
  }
  state.SetLabel(files[state.range(0)]);
  std::size_t points = 0;
  for (auto _ : state) points = io::read_point_cloud(path).size();
  state.counters["points/s"] = benchmark::Counter(static_cast<double>(points),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_ReadPcd)->DenseRange(0, 2)->Unit(benchmark::kMillisecond)->UseRealTime();

// One Redwood frame as the sequence reader delivers it (what the source node does per frame):
// the 16-bit depth PNG and the colour image decoded, with its intrinsics and pose.
void BM_LoadDepthFrame(benchmark::State& state) {
  const std::string dir = data_dir() + "/rgbd_redwood";
  if (!std::filesystem::exists(dir)) {
    state.SkipWithError((dir + " not found").c_str());
    return;
  }
  const auto sequence = io::open_sequence(dir);
  const io::SequenceFrame frame = sequence->frame(0);
  std::size_t pixels = 0;
  for (auto _ : state) pixels = frame.load_depth().depth.pixels();
  state.counters["pixels/s"] = benchmark::Counter(static_cast<double>(pixels),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_LoadDepthFrame)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace meshflow::bench
