#include "bench_support.h"
#include "nodes/optimize/mesh_cleanup.h"
#include "runtime/threads.h"

namespace meshflow::bench {
namespace {

void BM_MeshCleanup(benchmark::State& state) {
  if (require(state, static_cast<Input>(state.range(1))) == nullptr) return;
  const Frame* f = prepared_frame(static_cast<Input>(state.range(1)), "optimize");
  ThreadLimit limit(static_cast<int>(state.range(0)));
  for (auto _ : state)
    benchmark::DoNotOptimize(clean_mesh(f->mesh, CleanupConfig{}).triangles.size());
  state.counters["triangles/s"] = benchmark::Counter(static_cast<double>(f->mesh.triangles.size()),
                                                     benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_MeshCleanup)->Apply(thread_and_input_args);

}  // namespace
}  // namespace meshflow::bench
