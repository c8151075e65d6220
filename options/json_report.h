#pragma once
// The --json documents of the subcommands, built with nlohmann-json. Field names are
// snake_case, lengths in metres, times in milliseconds unless the name says otherwise
// (docs/JSON.md lists them).

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "graph/frame.h"
#include "graph/sequence_runner.h"
#include "nodes/chunk/phase_times.h"
#include "nodes/eval/surface_eval.h"
#include "runtime/tracing.h"

namespace meshflow::options {

/// {"mean", "rms", "median", "p95", "max", "samples"} in metres.
nlohmann::json distance_json(const DistanceStats& s);

/// {"mean", "median", "p5", "min", "vertices"}: per-vertex observation counts.
nlohmann::json observations_json(const std::vector<float>& counts);

/// {"edges", "boundary_edges", "non_manifold_edges", "inconsistent_edges", "boundary_loops",
/// "degenerate_faces", "watertight"}.
nlohmann::json topology_json(const MeshTopology& t);

/// One object per stage: {"stage", "calls", "total_ms", "mean_ms", "p50_ms", "p95_ms",
/// "max_ms", "items"}.
nlohmann::json stages_json(const std::vector<StageSummary>& summaries);

/// One object per optimize step: {"step", "triangles_in", "triangles_out", "ms", "skipped",
/// "detail"}.
nlohmann::json optimize_json(const OptimizeReport& report);

/// What the close stage did: {"ran", "filled", "observed", "seen_empty", "through",
/// "cells_added", "levels", "coarse_step", "tiles"}.
nlohmann::json close_json(const CloseReport& closing);

/// What the pipeline did to one frame: "input", "points", "filter", "normals", "voxel",
/// "grid", "mesh" {"vertices", "triangles", "extract"}, "optimize" (steps), "time_ms",
/// "threads", "stages".
nlohmann::json frame_json(const Frame& frame, double wall_s, int threads);

/// A sequence run: "sequence", "frames_ok", "frames_failed", "stopped_early", "wall_s",
/// "frames_per_second", "threads", "in_flight", "stages" (run/profile add "failed_frames":
/// index, file, stage and message of each failed frame; tools/run_commands.cpp).
nlohmann::json run_json(const std::string& sequence, const SequenceRunStats& stats, int threads,
                        std::size_t in_flight);

/// A chunked run's timing (reconstruct --chunk, meshflow-mpi reconstruct): {"ranks": one object
/// per process {"rank", "chunks", "peak_rss_mib", "phases": [{"phase", "wall_s", "cpu_s",
/// "work_s", "serial"}]}, "serial": {"serial_s", "parallel_work_s", "fraction", "max_speedup",
/// "wall_share", "speedup": {"2", "8", "32", "128"} workers by Amdahl's law}}.
nlohmann::json chunked_timing_json(const std::vector<chunk::RankTimes>& ranks, double wall_s);

}  // namespace meshflow::options
