#pragma once
// Where a fused map's surface goes (`meshflow run --fuse`): the pixels each filter stage drops,
// what integration did, and the cells extraction meshes, completes or leaves out — printed after
// the run, in --json, and per frame with -v.

#include <nlohmann/json.hpp>

#include <cstddef>

#include "graph/frame.h"
#include "nodes/fusion/tsdf_mesher.h"

namespace meshflow::cli {

class FusionBreakdown {
 public:
  /// Adds one fused frame's counts (and prints its line with -v). O(1).
  void add(const Frame& f);
  /// The run's figures with the extraction's cell counts: {"pixels": {"total", "unmeasured",
  /// "out_of_range", "occlusion_edges", "fused", "moved_by_smoothing"}, "noise_per_depth2_mean",
  /// "blocks_touched", "blocks_carved", "voxels_updated", "voxels_observed",
  /// "voxels_below_min_weight", "cells_meshed", "cells_completed_behind", "cells_left_out"}.
  nlohmann::json json(const TsdfCellCounts& cells) const;
  /// Prints the pixels, voxels and cells lines of the report.
  void print(const TsdfCellCounts& cells) const;

 private:
  double mean_noise() const;

  DepthFilterCounts pixels_;  // summed over the fused frames
  std::size_t frames_ = 0, blocks_touched_ = 0, blocks_carved_ = 0, voxels_updated_ = 0;
  double noise_sum_ = 0.0;  // of the frames' noise_per_depth2
};

}  // namespace meshflow::cli
