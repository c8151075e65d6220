#include "tools/fusion_breakdown.h"

#include "tools/console.h"

namespace meshflow::cli {
namespace {

double share(std::size_t part, std::size_t whole) {
  return whole ? 100.0 * static_cast<double>(part) / static_cast<double>(whole) : 0.0;
}

}  // namespace

void FusionBreakdown::add(const Frame& f) {
  const DepthFilterCounts c = f.depth ? f.depth->counts : DepthFilterCounts{};
  pixels_.pixels += c.pixels;
  pixels_.invalid += c.invalid;
  pixels_.out_of_range += c.out_of_range;
  pixels_.edges += c.edges;
  pixels_.valid += c.valid;
  pixels_.smoothed += c.smoothed;
  ++frames_;
  blocks_touched_ += f.integration.blocks_touched;
  blocks_carved_ += f.integration.blocks_carved;
  voxels_updated_ += f.integration.voxels_updated;
  noise_sum_ += f.integration.noise_per_depth2;
  detail(
      "frame      %s: %zu of %zu pixels fused (%zu unmeasured, %zu out of range, %zu "
      "occlusion edges); noise %.2e x depth^2; %zu blocks touched, %zu new, %zu carved; %zu "
      "voxels updated\n",
      f.name.c_str(), c.valid, c.pixels, c.invalid, c.out_of_range, c.edges,
      static_cast<double>(f.integration.noise_per_depth2), f.integration.blocks_touched,
      f.integration.blocks_allocated, f.integration.blocks_carved, f.integration.voxels_updated);
}

double FusionBreakdown::mean_noise() const {
  return frames_ ? noise_sum_ / static_cast<double>(frames_) : 0.0;
}

nlohmann::json FusionBreakdown::json(const TsdfCellCounts& c) const {
  return {{"pixels",
           {{"total", pixels_.pixels},
            {"unmeasured", pixels_.invalid},
            {"out_of_range", pixels_.out_of_range},
            {"occlusion_edges", pixels_.edges},
            {"fused", pixels_.valid},
            {"moved_by_smoothing", pixels_.smoothed}}},
          {"noise_per_depth2_mean", mean_noise()},
          {"blocks_touched", blocks_touched_},
          {"blocks_carved", blocks_carved_},
          {"voxels_updated", voxels_updated_},
          {"voxels_observed", c.voxels_observed},
          {"voxels_below_min_weight", c.voxels_below_weight},
          {"cells_meshed", c.cells_meshed},
          {"cells_completed_behind", c.cells_completed},
          {"cells_left_out", c.cells_left_out}};
}

void FusionBreakdown::print(const TsdfCellCounts& c) const {
  report(
      "pixels     %.1f %% fused; dropped: %.1f %% unmeasured, %.1f %% out of range, %.1f %% "
      "occlusion edges, none by smoothing (it moved %.1f %%)\n",
      share(pixels_.valid, pixels_.pixels), share(pixels_.invalid, pixels_.pixels),
      share(pixels_.out_of_range, pixels_.pixels), share(pixels_.edges, pixels_.pixels),
      share(pixels_.smoothed, pixels_.pixels));
  report(
      "voxels     %zu observed, %zu at or below --min-weight; depth noise %.2e x depth^2 "
      "(mean over frames); %zu blocks carved as free space (summed over frames)\n",
      c.voxels_observed, c.voxels_below_weight, mean_noise(), blocks_carved_);
  report(
      "cells      %zu meshed (%zu completed behind the surface), %zu left out beside "
      "unobserved space (%.2f %%)\n",
      c.cells_meshed, c.cells_completed, c.cells_left_out,
      share(c.cells_left_out, c.cells_meshed + c.cells_left_out));
}

}  // namespace meshflow::cli
