#pragma once
// Console reports shared by the subcommands.

#include <string>
#include <vector>

#include "graph/frame.h"

namespace meshflow::cli {

/// Prints what the pipeline did to one frame (counts, voxel size, stage table) to stdout.
void print_frame_report(const Frame& frame, double wall_s, int threads);

/// One line on where a cloud's normals came from: "from the input", "from the input, 12
/// missing ... estimated", or "estimated (kn 10, median plane-fit variation 0.001), oriented by
/// propagation (1 component, 3 turned by the vote)".
std::string describe_normals(const NormalsReport& report);

/// Why automatic propagation turned a scene of this kind as it did, for the console: e.g.
/// "up (LAS or map coordinates: heights along z)". Static text.
const char* scene_rule(SceneKind kind);

/// One console line on per-vertex observation counts (`what` each counts, e.g. "points within
/// one voxel"): median, 5th percentile, minimum, and the PLY property that holds them.
void report_observations(const std::vector<float>& counts, const char* what);

/// Prints the close stage's line ("close      N corners filled by diffusion ...") when it ran.
void report_closing(const CloseReport& closing);

/// Throws meshflow::Error carrying the frame's error if it failed.
void throw_if_failed(const Frame& frame);

}  // namespace meshflow::cli
