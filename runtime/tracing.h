#pragma once
// Per-stage timing records, cheap enough to keep on for every frame.

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

namespace meshflow {

/// Seconds on a monotonic clock since the first call in this process. Thread-safe.
double monotonic_seconds();

/// Small dense id of the calling thread (0 for the first thread that asks). Thread-safe.
std::uint32_t current_thread_index();

/// One execution of one stage on one frame.
struct StageRecord {
  std::string stage;         ///< stage name, e.g. "normals"
  double start_s = 0.0;      ///< monotonic_seconds() at start
  double end_s = 0.0;        ///< monotonic_seconds() at end
  std::uint32_t thread = 0;  ///< current_thread_index() of the thread that started it
  std::uint64_t items = 0;   ///< work items the stage processed (points, corners, triangles)
  double duration_s() const { return end_s - start_s; }
};

/// Summary of many records of one stage (e.g. all frames of a run).
struct StageSummary {
  std::string stage;
  std::size_t calls = 0;
  double total_s = 0.0, mean_s = 0.0, p50_s = 0.0, p95_s = 0.0, max_s = 0.0;
  std::uint64_t items = 0;
};

/// Groups records by stage, in order of first appearance. O(n log n).
std::vector<StageSummary> summarize_stages(const std::vector<StageRecord>& records);

/// Human-readable table of `summaries`; share of wall time relative to `wall_s`.
std::string format_stage_table(const std::vector<StageSummary>& summaries, double wall_s);

}  // namespace meshflow
