// The QEM decimation itself is timed as an optimize step (BM_OptimizeStep, step 3) on the
// same meshes; this file holds the reference it is compared with.

#include <algorithm>
#include <cstddef>

#include "bench_support.h"

#ifdef MESHFLOW_HAVE_MESHOPTIMIZER
#include <meshoptimizer.h>
#endif

namespace meshflow::bench {
namespace {

#ifdef MESHFLOW_HAVE_MESHOPTIMIZER
// The reference: meshoptimizer's simplifier (edge collapses with quadrics, single-threaded) to
// 25 % of the triangles, no error limit, on the same mesh.
void BM_MeshoptSimplify(benchmark::State& state) {
  const TriangleMesh* mesh = cleaned_mesh(state);
  if (mesh == nullptr) return;
  const std::size_t indices = mesh->triangles.size() * 3;
  std::vector<unsigned int> out(indices);
  std::size_t kept = 0;
  for (auto _ : state) {
    kept = meshopt_simplify(out.data(), mesh->triangles.front().data(), indices,
                            mesh->vertices.front().data(), mesh->vertices.size(),
                            sizeof(Eigen::Vector3f), indices / 4, 1.0f, 0, nullptr);
    benchmark::DoNotOptimize(out.data());
  }
  count_triangles(state, *mesh, kept / 3);
  if (kept == 0) return;
  TriangleMesh simplified;
  simplified.vertices = mesh->vertices;  // (unused ones are no surface)
  simplified.triangles.resize(kept / 3);
  std::copy(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(kept),
            simplified.triangles.front().data());
  count_distance_to_input(state, *mesh, simplified);
}
BENCHMARK(BM_MeshoptSimplify)
    ->ArgsProduct({{1}, {kSynthetic, kKurt3d}})
    ->ArgNames({"threads", "input"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
#endif

}  // namespace
}  // namespace meshflow::bench
