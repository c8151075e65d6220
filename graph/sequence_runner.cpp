#include "graph/sequence_runner.h"

#include <algorithm>
#include <atomic>

namespace meshflow {

SequenceRunStats run_sequence(FramePipeline& pipeline, const io::Sequence& sequence,
                              const SequenceRunOptions& options,
                              const std::function<void(const Frame&)>& on_frame) {
  SequenceRunStats stats;
  const std::size_t every = std::max<std::size_t>(1, options.every);
  std::size_t next_index = 0, fed = 0;
  std::atomic<bool> stop{false};
  const double t0 = monotonic_seconds();
  pipeline.run(
      [&]() -> FramePtr {
        if (stop.load() || next_index >= sequence.size() ||
            (options.max_frames > 0 && fed >= options.max_frames)) {
          return nullptr;
        }
        io::SequenceFrame source = sequence.frame(next_index);
        next_index += every;
        ++fed;
        auto frame = std::make_shared<Frame>();
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
