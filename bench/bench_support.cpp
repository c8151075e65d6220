#include "bench_support.h"

#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>

#include "graph/stages.h"
#include "nodes/eval/surface_eval.h"
#include "nodes/io/scan3d_reader.h"
#include "nodes/io/sequence.h"
#include "nodes/optimize/cleanup/mesh_cleanup.h"
#include "nodes/synthetic/depth_sequence.h"
#include "nodes/synthetic/scan_simulator.h"
#include "runtime/threads.h"

namespace meshflow::bench {

std::string data_dir() {
  const char* env = std::getenv("MESHFLOW_DATA");
  return env != nullptr && *env != '\0' ? env
                                        : std::string(MESHFLOW_SOURCE_DIR) + "/../shared/data";
}

std::string kurt3d_path() { return data_dir() + "/kurt3d/scan000.3d"; }

const PointCloud* input_cloud(Input input) {
  static const PointCloud synthetic = [] {
    synthetic::ScanConfig scan;  // 500 x 200 rays = 100k points in the demo room
    scan.azimuth_steps = 500;
    scan.elevation_steps = 200;
    scan.noise_sigma = 0.002f;
    return synthetic::simulate_scan(synthetic::demo_room_scene(), scan);
  }();
  static const std::unique_ptr<PointCloud> kurt = []() -> std::unique_ptr<PointCloud> {
    if (!std::filesystem::exists(kurt3d_path())) return nullptr;
    return std::make_unique<PointCloud>(io::read_3dtk_scan(kurt3d_path()));
  }();
  return input == kSynthetic ? &synthetic : kurt.get();
}

const Frame* prepared_frame(Input input, const std::string& stage) {
  static std::map<std::pair<int, std::string>, std::unique_ptr<Frame>> cache;
  auto& slot = cache[{input, stage}];
  if (slot) return slot.get();
  const PointCloud* cloud = input_cloud(input);
  if (cloud == nullptr) return nullptr;
  ReconstructionConfig config;
  config.voxelize.voxel_size = 0.05f;
  slot = std::make_unique<Frame>();
  slot->cloud = *cloud;
  for (const stages::NamedStage& s : stages::kPointCloudStages) {
    if (stage == s.name) break;
    stages::run_stage(s.name, s.body, *slot, config);  // "read" is a no-op: no loader set
  }
  return slot.get();
}

const PointCloud* require(benchmark::State& state, Input input) {
  const PointCloud* cloud = input_cloud(input);
  if (cloud == nullptr) state.SkipWithError(("kurt3d data not found at " + kurt3d_path()).c_str());
  return cloud;
}

const TriangleMesh* extracted_mesh(benchmark::State& state) {
  if (require(state, static_cast<Input>(state.range(1))) == nullptr) return nullptr;
  return &prepared_frame(static_cast<Input>(state.range(1)), "optimize")->mesh;
}

const TriangleMesh* cleaned_mesh(benchmark::State& state) {
  static std::map<std::int64_t, TriangleMesh> cache;
  const TriangleMesh* raw = extracted_mesh(state);
  if (raw == nullptr) return nullptr;
  auto it = cache.find(state.range(1));
  if (it == cache.end()) it = cache.emplace(state.range(1), clean_mesh(*raw, {})).first;
  return &it->second;
}

void count_triangles(benchmark::State& state, const TriangleMesh& in, std::size_t out) {
  state.counters["triangles/s"] = benchmark::Counter(static_cast<double>(in.triangles.size()),
                                                     benchmark::Counter::kIsIterationInvariantRate);
  state.counters["in"] = static_cast<double>(in.triangles.size());
  state.counters["out"] = static_cast<double>(out);
}

void count_distance_to_input(benchmark::State& state, const TriangleMesh& input,
                             const TriangleMesh& output) {
  const DistanceStats d = evaluate_surface(output, input).reference_to_mesh;
  state.counters["dist_mean_mm"] = 1e3 * d.mean;
  state.counters["dist_p95_mm"] = 1e3 * d.p95;
}

void time_optimize(benchmark::State& state, const TriangleMesh& mesh, const OptimizeConfig& config,
                   const std::vector<std::uint8_t>* feature_vertices) {
  ThreadLimit limit(static_cast<int>(state.range(0)));
  std::size_t out = 0;
  for (auto _ : state)
    benchmark::DoNotOptimize(out = (feature_vertices
                                        ? optimize_mesh(mesh, config, nullptr, *feature_vertices)
                                        : optimize_mesh(mesh, config))
                                       .triangles.size());
  count_triangles(state, mesh, out);
}

void thread_and_input_args(benchmark::internal::Benchmark* b) {
  b->ArgNames({"threads", "input"});
  for (int input : {kSynthetic, kKurt3d})
    for (int threads : {1, 2}) b->Args({threads, input});
  b->Unit(benchmark::kMillisecond)->UseRealTime();
}

const std::vector<DepthFrame>& depth_frames(bool redwood) {
  static const std::vector<DepthFrame> real = [] {
    std::vector<DepthFrame> out;
    const std::string dir = data_dir() + "/rgbd_redwood";
    if (!std::filesystem::exists(dir)) return out;
    const auto seq = io::open_sequence(dir);
    for (std::size_t i = 0; i < seq->size(); ++i) out.push_back(seq->frame(i).load_depth());
    return out;
  }();
  static const std::vector<DepthFrame> synthetic = [] {
    synthetic::DepthSequenceConfig c;
    c.frames = 40;  // 9 degrees apart; the first 5 are used
    const auto seq = synthetic::make_depth_sequence(synthetic::demo_room_scene(), c);
    std::vector<DepthFrame> out;
    for (std::size_t i = 0; i < 5; ++i) out.push_back(seq->frame(i).load_depth());
    return out;
  }();
  return redwood ? real : synthetic;
}

const std::vector<DepthFrame>* require_depth_frames(benchmark::State& state, bool redwood) {
  const std::vector<DepthFrame>& frames = depth_frames(redwood);
  if (!frames.empty()) return &frames;
  state.SkipWithError(("Redwood frames not found at " + data_dir() + "/rgbd_redwood").c_str());
  return nullptr;
}

}  // namespace meshflow::bench
