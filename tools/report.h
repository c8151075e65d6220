#pragma once
// Console reports shared by the subcommands.

#include <string>

#include "graph/frame.h"

namespace meshflow::cli {

/// Prints what the pipeline did to one frame (counts, voxel size, stage table) to stdout.
void print_frame_report(const Frame& frame, double wall_s, int threads);

/// Throws meshflow::Error carrying the frame's error if it failed.
void throw_if_failed(const Frame& frame);

}  // namespace meshflow::cli
