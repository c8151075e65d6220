#include <cmath>

#include "bench_support.h"
#include "nodes/optimize/planar/planar_regions.h"
#include "nodes/texture/region_textures.h"
#include "runtime/half_edge_mesh.h"
#include "runtime/threads.h"

namespace meshflow::bench {
namespace {

// Texture generation for the planar regions of the cleaned mesh, from the frame's points
// coloured by position (the benchmark inputs have no colours), 1 cm texels.
void BM_TexturePlanarRegions(benchmark::State& state) {
  const TriangleMesh* mesh = cleaned_mesh(state);
  if (mesh == nullptr) return;
  PointCloud points;
  points.positions =
      prepared_frame(static_cast<Input>(state.range(1)), "optimize")->cloud.positions;
  for (const Eigen::Vector3f& p : points.positions)
    points.colors.push_back(Rgb8{static_cast<std::uint8_t>(std::lround(p.x() * 40.0f) & 255),
                                 static_cast<std::uint8_t>(std::lround(p.y() * 40.0f) & 255),
                                 static_cast<std::uint8_t>(std::lround(p.z() * 40.0f) & 255)});
  const PlanarSegmentation regions = grow_planar_regions(HalfEdgeMesh(*mesh));
  ThreadLimit limit(static_cast<int>(state.range(0)));
  std::size_t textures = 0;
  for (auto _ : state)
    benchmark::DoNotOptimize(textures =
                                 texture_planar_regions(*mesh, regions, points).textures.size());
  state.counters["textures"] = static_cast<double>(textures);
}
BENCHMARK(BM_TexturePlanarRegions)->Apply(thread_and_input_args);

}  // namespace
}  // namespace meshflow::bench
