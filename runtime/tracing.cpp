#include "runtime/tracing.h"

#include <algorithm>
#include <atomic>
#include <cstdio>

namespace meshflow {

double monotonic_seconds() {
  static const auto epoch = std::chrono::steady_clock::now();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - epoch).count();
}

std::uint32_t current_thread_index() {
  static std::atomic<std::uint32_t> next{0};
  thread_local const std::uint32_t index = next.fetch_add(1);
  return index;
}

std::vector<StageSummary> summarize_stages(const std::vector<StageRecord>& records) {
  std::vector<StageSummary> out;
  std::vector<std::vector<double>> durations;
  for (const StageRecord& r : records) {
    auto it = std::find_if(out.begin(), out.end(),
                           [&](const StageSummary& s) { return s.stage == r.stage; });
    if (it == out.end()) {
      out.push_back(StageSummary{r.stage});
      durations.emplace_back();
      it = out.end() - 1;
    }
    durations[static_cast<std::size_t>(it - out.begin())].push_back(r.duration_s());
    it->items += r.items;
  }
  for (std::size_t i = 0; i < out.size(); ++i) {
    auto& d = durations[i];
    std::sort(d.begin(), d.end());
    StageSummary& s = out[i];
    s.calls = d.size();
    for (double v : d) s.total_s += v;
    s.mean_s = s.total_s / static_cast<double>(d.size());
    s.p50_s = d[d.size() / 2];
    s.p95_s =
        d[std::min(d.size() - 1, static_cast<std::size_t>(0.95 * static_cast<double>(d.size())))];
    s.max_s = d.back();
  }
  return out;
}

std::string format_stage_table(const std::vector<StageSummary>& summaries, double wall_s) {
  std::string out;
  char line[256];
  std::snprintf(line, sizeof line, "%-12s %6s %10s %10s %10s %7s %14s\n", "stage", "calls",
                "mean ms", "p95 ms", "max ms", "share", "items/s");
  out += line;
  for (const StageSummary& s : summaries) {
    const double share = wall_s > 0.0 ? 100.0 * s.total_s / wall_s : 0.0;
    const double rate = s.total_s > 0.0 ? static_cast<double>(s.items) / s.total_s : 0.0;
    std::snprintf(line, sizeof line, "%-12s %6zu %10.2f %10.2f %10.2f %6.1f%% %14.3g\n",
                  s.stage.c_str(), s.calls, 1e3 * s.mean_s, 1e3 * s.p95_s, 1e3 * s.max_s, share,
                  rate);
    out += line;
  }
  return out;
}

}  // namespace meshflow
