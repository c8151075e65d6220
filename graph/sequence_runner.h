#pragma once
// Runs a recorded sequence through a frame pipeline (per-frame meshing or fusion): frame selection,
// strict mode and the accounting that `meshflow run` and `meshflow profile` report.

#include <cstddef>
#include <functional>
#include <vector>

#include "graph/pipeline.h"
#include "nodes/io/sequence.h"
#include "runtime/tracing.h"

namespace meshflow {

struct SequenceRunOptions {
  std::size_t every = 1;       ///< take every N-th frame of the sequence
  std::size_t max_frames = 0;  ///< stop after this many frames (0 = all)
  bool strict = false;         ///< stop feeding frames after the first failed one
  /// Keep every stage record of every frame in SequenceRunStats::records (for a Chrome trace);
  /// memory then grows with the frames. Off: only the bounded SequenceRunStats::stages.
  bool keep_records = false;
};

struct SequenceRunStats {
  std::size_t frames_ok = 0;
  std::size_t frames_failed = 0;
  bool stopped_early = false;        ///< strict mode hit a failed frame
  double wall_s = 0.0;               ///< from the first frame requested to the last delivered
  StageStatistics stages;            ///< per-stage timings of every frame (bounded memory)
  std::vector<StageRecord> records;  ///< with keep_records: every stage of every frame, in order
  /// Frames (ok or failed) per wall-clock second; 0 before any.
  double frames_per_second() const {
    return wall_s > 0.0 ? static_cast<double>(frames_ok + frames_failed) / wall_s : 0.0;
  }
};

/// Feeds the selected frames of `sequence` through `pipeline` and calls `on_frame` for each
/// finished frame, in sequence order, one at a time (failed frames included, `error` set).
/// In strict mode, frames after the first failure are neither fed nor delivered.
/// Frames are released after `on_frame` returns, so memory stays bounded by the frames in flight.
SequenceRunStats run_sequence(FramePipeline& pipeline, const io::Sequence& sequence,
                              const SequenceRunOptions& options,
                              const std::function<void(const Frame&)>& on_frame);

}  // namespace meshflow
