// Reconstructs a synthetic sphere through the installed meshflow library: once as a batch call
// and once through the embedding API (push frames, meshes arrive in a callback).
#include <cstdio>

#include "graph/live_pipeline.h"
#include "graph/pipeline.h"
#include "nodes/synthetic/shapes.h"

int main() {
  meshflow::ReconstructionConfig config;
  config.voxelize.voxel_size = 0.1f;
  config.normals.orientation = meshflow::NormalOrientation::kAwayFromViewpoint;
  const auto cloud =
      meshflow::synthetic::sample_surface(meshflow::synthetic::Sphere{}, 0.03f, 0.0f, 1);
  const auto frame = meshflow::ReconstructionPipeline(config).reconstruct(cloud, "sphere");
  if (!frame->ok() || frame->mesh.triangles.empty()) {
    std::fprintf(stderr, "consumer: reconstruction failed: %s\n", frame->error.c_str());
    return 1;
  }
  std::printf("consumer: %zu points -> %zu triangles\n", cloud.size(),
              frame->mesh.triangles.size());

  meshflow::LiveConfig live_config;
  live_config.reconstruction = config;
  live_config.policy = meshflow::LivePolicy::kQueue;
  std::size_t meshes = 0;
  {
    meshflow::LivePipeline live(live_config, [&](meshflow::LiveResult& r) {
      meshes += r.ok && !r.mesh.triangles.empty() ? 1 : 0;
    });
    for (int i = 0; i < 3; ++i) live.push(cloud);
    live.flush();
  }
  std::printf("consumer: live API delivered %zu of 3 meshes\n", meshes);
  return meshes == 3 ? 0 : 1;
}
