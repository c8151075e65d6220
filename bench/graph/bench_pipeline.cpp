#include <filesystem>

#include "bench_support.h"
#include "graph/pipeline.h"
#include "nodes/io/mesh_writers.h"
#include "nodes/io/read_point_cloud.h"
#include "runtime/threads.h"

namespace meshflow::bench {
namespace {

// Everything from file read to written mesh (kurt3d) or from the in-memory cloud to a written
// mesh (synthetic), at 5 cm voxels, through the flow graph.
void BM_PipelineEndToEnd(benchmark::State& state) {
  const auto input = static_cast<Input>(state.range(1));
  const PointCloud* cloud = require(state, input);
  if (cloud == nullptr) return;
  ThreadLimit limit(static_cast<int>(state.range(0)));
  ReconstructionConfig config;
  config.voxelize.voxel_size = 0.05f;
  ReconstructionPipeline pipeline(config, 1);
  const std::string out =
      (std::filesystem::temp_directory_path() / "meshflow_bench_mesh.ply").string();
  for (auto _ : state) {
    auto frame = std::make_shared<Frame>();
    if (input == kKurt3d) {
      frame->load = [] { return io::read_point_cloud(kurt3d_path()); };
    } else {
      frame->cloud = *cloud;
    }
    bool given = false;
    pipeline.run([&]() -> FramePtr { return given ? nullptr : (given = true, frame); },
                 [&](const FramePtr& f) { io::write_mesh(out, f->mesh); });
    if (!frame->ok()) state.SkipWithError(frame->error.c_str());
  }
  std::filesystem::remove(out);
  state.counters["points/s"] = benchmark::Counter(static_cast<double>(cloud->size()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_PipelineEndToEnd)->Apply(thread_and_input_args);

}  // namespace
}  // namespace meshflow::bench
