#include "graph/sequence_runner.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

namespace meshflow {

SequenceRunStats run_sequence(FramePipeline& pipeline, const io::Sequence& sequence,
                              const SequenceRunOptions& options,
                              const std::function<void(const Frame&)>& on_frame) {
  SequenceRunStats stats;
  const std::size_t every = std::max<std::size_t>(1, options.every);
  std::vector<std::size_t> selected;  // one loop's frames
  for (std::size_t i = 0; i < sequence.size(); i += every) {
    if (options.max_frames > 0 && selected.size() >= options.max_frames) break;
    selected.push_back(i);
  }
  const std::size_t total = selected.size() * std::max<std::size_t>(1, options.loops);
  std::size_t fed = 0;
  std::atomic<bool> stop{false};
  const double t0 = monotonic_seconds();
  pipeline.run(
      [&]() -> FramePtr {
        if (stop.load() || fed >= total) return nullptr;
        double submitted_s = monotonic_seconds();
        if (options.rate_hz > 0.0 && options.drop_late) {
          // The newest frame due by now (its release passed), if that is past the next one.
          const auto due = static_cast<std::size_t>((submitted_s - t0) * options.rate_hz);
          if (due > fed) {
            const std::size_t last = std::min(due, total - 1);
            stats.frames_dropped += last - fed;
            fed = last;
          }
        }
        if (options.rate_hz > 0.0) {
          const double release_s = t0 + static_cast<double>(fed) / options.rate_hz;
          if (release_s > submitted_s)
            std::this_thread::sleep_for(std::chrono::duration<double>(release_s - submitted_s));
          submitted_s = release_s;
        }
        io::SequenceFrame source = sequence.frame(selected[fed % selected.size()]);
        ++fed;
        auto frame = std::make_shared<Frame>();
        frame->submitted_s = submitted_s;
        frame->name = source.name;
        frame->source_index = source.index;
        frame->timestamp_s = source.timestamp_s;
        frame->load = std::move(source.load);
        frame->load_depth = std::move(source.load_depth);
        return frame;
      },
      [&](const FramePtr& f) {
        if (stats.stopped_early) return;  // strict: drop what was in flight behind the failure
        for (const StageRecord& r : f->timings) stats.stages.add(r);
        if (options.keep_records)
          stats.records.insert(stats.records.end(), f->timings.begin(), f->timings.end());
        if (f->ok()) {
          ++stats.frames_ok;
        } else {
          ++stats.frames_failed;
          if (options.strict) {
            stats.stopped_early = true;
            stop.store(true);
          }
        }
        on_frame(*f);
      });
  stats.wall_s = monotonic_seconds() - t0;
  return stats;
}

}  // namespace meshflow
