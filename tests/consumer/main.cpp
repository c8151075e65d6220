// Reconstructs a synthetic sphere through the installed meshflow library.
#include <cstdio>

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
  return 0;
}
