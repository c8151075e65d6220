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
  std::uint64_t frame = 0;   ///< sequence number of the frame it worked on
  /// end_s - start_s.
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

/// The same summaries, accumulated record by record in memory that does not grow with the
/// number of records (a run of a million frames holds what a run of ten does): calls, total,
/// mean, max and items exact; p50 and p95 from a histogram of bins 1 % wide (1 us to 7 min; longer
/// counts as 7 min), so within 1 % of the exact ones. Not thread-safe.
class StageStatistics {
 public:
  /// O(stages).
  void add(const StageRecord& record);
  /// In order of each stage's first record. O(stages x bins).
  std::vector<StageSummary> summaries() const;

 private:
  struct Stage {
    StageSummary summary;
    std::vector<std::uint32_t> histogram;  // calls per duration bin
  };
  std::vector<Stage> stages_;
};

/// Human-readable table of `summaries`: calls, mean, p50, p95, max (ms), share of all stage
/// time, work items/s; then the busy/wall ratio (average number of stages running at once).
std::string format_stage_table(const std::vector<StageSummary>& summaries, double wall_s);

/// The same table as CSV (header line, one row per stage, times in milliseconds).
std::string format_stage_csv(const std::vector<StageSummary>& summaries, double wall_s);

/// Chrome trace-event JSON ("X" complete events, one per record: name = stage,
/// tid = thread index, args = frame and items), loadable in Perfetto and chrome://tracing.
/// Timestamps are microseconds relative to the earliest record.
std::string chrome_trace_json(const std::vector<StageRecord>& records);

}  // namespace meshflow
