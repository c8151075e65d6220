#pragma once
// What integrating one depth frame into a TSDF map did (TsdfFrameIntegrator::integrate): the
// report a fused frame carries through the graph.

#include <cstddef>

namespace meshflow {

/// Counts from one integrate() call, for reports and the per-frame JSON.
struct IntegrationStats {
  float noise_per_depth2 = 0.0f;     ///< the frame's depth noise estimate (1/m), for the band
  std::size_t pixels_used = 0;       ///< valid depth pixels
  std::size_t blocks_touched = 0;    ///< blocks the truncation band passes through
  std::size_t blocks_allocated = 0;  ///< of which new
  std::size_t voxels_updated = 0;    ///< voxels whose distance was fused (carved ones too)
  std::size_t blocks_carved = 0;     ///< untouched blocks updated as free space
};

}  // namespace meshflow
