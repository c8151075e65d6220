#include "runtime/tracing.h"

#include <algorithm>
#include <atomic>
#include <cmath>
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

namespace {

// Duration bins of StageStatistics: bin b holds durations in [kFirstBin * kBinRatio^(b-1),
// kFirstBin * kBinRatio^b); bin 0 everything shorter, the last everything longer.
constexpr double kFirstBin = 1e-6, kBinRatio = 1.01;
constexpr std::size_t kBins = 2000;  // the last starts at 1.01^1998 x 1 us = 7.2 min

std::size_t bin_of(double seconds) {
  if (!(seconds > kFirstBin)) return 0;
  const double b = std::ceil(std::log(seconds / kFirstBin) / std::log(kBinRatio));
  return std::min(kBins - 1, static_cast<std::size_t>(b));
}

// The geometric middle of bin b's range (its upper edge for bin 0).
double bin_value(std::size_t b) {
  if (b == 0) return kFirstBin;
  return kFirstBin * std::pow(kBinRatio, static_cast<double>(b) - 0.5);
}

// The duration below which `share` of the histogram's calls lie, clamped to [min, max].
double histogram_quantile(const std::vector<std::uint32_t>& histogram, std::size_t calls,
                          double share, double max_s) {
  const auto rank =
      std::min(calls - 1, static_cast<std::size_t>(share * static_cast<double>(calls)));
  std::size_t seen = 0;
  for (std::size_t b = 0; b < histogram.size(); ++b) {
    seen += histogram[b];
    if (seen > rank) return std::min(bin_value(b), max_s);
  }
  return max_s;
}

}  // namespace

void StageStatistics::add(const StageRecord& record) {
  auto it = std::find_if(stages_.begin(), stages_.end(),
                         [&](const Stage& s) { return s.summary.stage == record.stage; });
  if (it == stages_.end()) {
    stages_.push_back(Stage{StageSummary{record.stage}, std::vector<std::uint32_t>(kBins, 0)});
    it = stages_.end() - 1;
  }
  const double d = record.duration_s();
  StageSummary& s = it->summary;
  ++s.calls;
  s.total_s += d;
  s.max_s = s.calls == 1 ? d : std::max(s.max_s, d);
  s.items += record.items;
  ++it->histogram[bin_of(d)];
}

std::vector<StageSummary> StageStatistics::summaries() const {
  std::vector<StageSummary> out;
  for (const Stage& stage : stages_) {
    StageSummary s = stage.summary;
    s.mean_s = s.total_s / static_cast<double>(s.calls);
    s.p50_s = histogram_quantile(stage.histogram, s.calls, 0.5, s.max_s);
    s.p95_s = histogram_quantile(stage.histogram, s.calls, 0.95, s.max_s);
    out.push_back(s);
  }
  return out;
}

namespace {
double total_stage_seconds(const std::vector<StageSummary>& summaries) {
  double total = 0.0;
  for (const StageSummary& s : summaries) total += s.total_s;
  return total;
}
}  // namespace

std::string format_stage_table(const std::vector<StageSummary>& summaries, double wall_s) {
  std::string out;
  char line[256];
  const double busy = total_stage_seconds(summaries);
  std::snprintf(line, sizeof line, "%-10s %6s %9s %9s %9s %9s %7s %12s\n", "stage", "calls",
                "mean ms", "p50 ms", "p95 ms", "max ms", "share", "items/s");
  out += line;
  for (const StageSummary& s : summaries) {
    const double share = busy > 0.0 ? 100.0 * s.total_s / busy : 0.0;
    const double rate = s.total_s > 0.0 ? static_cast<double>(s.items) / s.total_s : 0.0;
    std::snprintf(line, sizeof line, "%-10s %6zu %9.2f %9.2f %9.2f %9.2f %6.1f%% %12.3g\n",
                  s.stage.c_str(), s.calls, 1e3 * s.mean_s, 1e3 * s.p50_s, 1e3 * s.p95_s,
                  1e3 * s.max_s, share, rate);
    out += line;
  }
  if (wall_s > 0.0) {
    std::snprintf(line, sizeof line, "stage time / wall time = %.2f (stages running at once)\n",
                  busy / wall_s);
    out += line;
  }
  return out;
}

std::string format_stage_csv(const std::vector<StageSummary>& summaries, double wall_s) {
  std::string out =
      "stage,calls,total_ms,mean_ms,p50_ms,p95_ms,max_ms,share,items,items_per_s,wall_ms\n";
  const double busy = total_stage_seconds(summaries);
  char line[320];
  for (const StageSummary& s : summaries) {
    std::snprintf(line, sizeof line, "%s,%zu,%.4f,%.4f,%.4f,%.4f,%.4f,%.5f,%llu,%.6g,%.4f\n",
                  s.stage.c_str(), s.calls, 1e3 * s.total_s, 1e3 * s.mean_s, 1e3 * s.p50_s,
                  1e3 * s.p95_s, 1e3 * s.max_s, busy > 0.0 ? s.total_s / busy : 0.0,
                  static_cast<unsigned long long>(s.items),
                  s.total_s > 0.0 ? static_cast<double>(s.items) / s.total_s : 0.0, 1e3 * wall_s);
    out += line;
  }
  return out;
}

std::string chrome_trace_json(const std::vector<StageRecord>& records) {
  double t0 = records.empty() ? 0.0 : records.front().start_s;
  for (const StageRecord& r : records) t0 = std::min(t0, r.start_s);
  std::string out = "{\"displayTimeUnit\":\"ms\",\"traceEvents\":[";
  char event[384];
  for (std::size_t i = 0; i < records.size(); ++i) {
    const StageRecord& r = records[i];
    // Stage names are meshflow's own identifiers (no characters that need JSON escaping).
    std::snprintf(event, sizeof event,
                  "%s\n{\"name\":\"%s\",\"cat\":\"stage\",\"ph\":\"X\",\"ts\":%.3f,\"dur\":%.3f,"
                  "\"pid\":1,\"tid\":%u,\"args\":{\"frame\":%llu,\"items\":%llu}}",
                  i == 0 ? "" : ",", r.stage.c_str(), 1e6 * (r.start_s - t0), 1e6 * r.duration_s(),
                  r.thread, static_cast<unsigned long long>(r.frame),
                  static_cast<unsigned long long>(r.items));
    out += event;
  }
  out += "\n]}\n";
  return out;
}

}  // namespace meshflow
