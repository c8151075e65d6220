#include "bench_support.h"
#include "nodes/extract/extract_surface.h"
#include "nodes/extract/rim_trim.h"
#include "runtime/threads.h"

namespace meshflow::bench {
namespace {

// Extraction by one method over the prepared grid (5 cm voxels); range(2) is the method.
void BM_Extract(benchmark::State& state) {
  if (require(state, static_cast<Input>(state.range(1))) == nullptr) return;
  const Frame* f = prepared_frame(static_cast<Input>(state.range(1)), "extract");
  ExtractConfig config;
  config.method = static_cast<ExtractMethod>(state.range(2));
  state.SetLabel(extract_method_name(config.method));
  ThreadLimit limit(static_cast<int>(state.range(0)));
  std::size_t triangles = 0;
  for (auto _ : state)
    triangles =
        extract_surface(f->grid, f->distance, f->cloud, f->index.get(), config).triangles.size();
  state.counters["cells/s"] = benchmark::Counter(static_cast<double>(f->grid.cells.size()),
                                                 benchmark::Counter::kIsIterationInvariantRate);
  state.counters["triangles"] = static_cast<double>(triangles);
}
BENCHMARK(BM_Extract)
    ->ArgNames({"threads", "input", "method"})
    ->ArgsProduct({{1, 2},
                   {kSynthetic, kKurt3d},
                   {static_cast<int>(ExtractMethod::kMarchingCubes),
                    static_cast<int>(ExtractMethod::kMarchingTetrahedra),
                    static_cast<int>(ExtractMethod::kPlanarMarchingCubes),
                    static_cast<int>(ExtractMethod::kExtendedMarchingCubes)}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Peeling the rim (1 voxel) of the marching-cubes mesh of the prepared grid, as "extract" does.
void BM_RimTrim(benchmark::State& state) {
  if (require(state, static_cast<Input>(state.range(1))) == nullptr) return;
  const Frame* f = prepared_frame(static_cast<Input>(state.range(1)), "extract");
  ExtractConfig config;
  config.method = ExtractMethod::kMarchingCubes;
  const TriangleMesh mesh = extract_surface(f->grid, f->distance, f->cloud, f->index.get(), config);
  ThreadLimit limit(static_cast<int>(state.range(0)));
  std::size_t removed = 0;
  for (auto _ : state)
    benchmark::DoNotOptimize(
        trim_rim(mesh, f->cloud.positions, *f->index, f->voxel_size, &removed));
  state.counters["triangles/s"] = benchmark::Counter(static_cast<double>(mesh.triangles.size()),
                                                     benchmark::Counter::kIsIterationInvariantRate);
  state.counters["removed"] = static_cast<double>(removed);
}
BENCHMARK(BM_RimTrim)
    ->ArgNames({"threads", "input"})
    ->ArgsProduct({{1, 2}, {kSynthetic, kKurt3d}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace meshflow::bench
