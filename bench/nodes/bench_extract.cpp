#include "bench_support.h"
#include "nodes/extract/marching_cubes.h"
#include "runtime/threads.h"

namespace meshflow::bench {
namespace {

void BM_MarchingCubes(benchmark::State& state) {
  if (require(state, static_cast<Input>(state.range(1))) == nullptr) return;
  const Frame* f = prepared_frame(static_cast<Input>(state.range(1)), "extract");
  ThreadLimit limit(static_cast<int>(state.range(0)));
  std::size_t triangles = 0;
  for (auto _ : state) triangles = marching_cubes(f->grid, f->distance).triangles.size();
  state.counters["cells/s"] = benchmark::Counter(static_cast<double>(f->grid.cells.size()),
                                                 benchmark::Counter::kIsIterationInvariantRate);
  state.counters["triangles"] = static_cast<double>(triangles);
}
BENCHMARK(BM_MarchingCubes)->Apply(thread_and_input_args);

}  // namespace
}  // namespace meshflow::bench
