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
  /// > 0: paced replay, as a sensor would deliver the frames: the source releases the n-th fed
  /// frame no sooner than n / rate_hz seconds after the run starts, and Frame::submitted_s is
  /// that release time. A graph slower than the rate keeps every frame: the source waits for a
  /// free slot (K frames in flight) and the frames queue behind it (nothing is dropped, so the
  /// files are those of an unpaced run); submitted_s stays the scheduled release, so the time
  /// a frame spent waiting counts in its latency. The source waits on one of the graph's
  /// threads. 0: frames are fed as fast as the graph takes them (submitted_s: when fed).
  double rate_hz = 0.0;
  /// With rate_hz, the realtime policy: when the source is behind its schedule (the graph was
  /// busy), it skips to the newest frame already due, dropping the older ones (counted in
  /// SequenceRunStats::frames_dropped), as a live sensor's driver would: latency stays bounded,
  /// the map integrates fewer frames. Off (queue): every frame is fed, late.
  bool drop_late = false;
  /// Feed the selected frames this many times over (seq keeps counting; source_index repeats).
  std::size_t loops = 1;
};

struct SequenceRunStats {
  std::size_t frames_ok = 0;
  std::size_t frames_failed = 0;
  std::size_t frames_dropped = 0;    ///< skipped by the realtime policy (drop_late)
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
/// Frame::submitted_s is monotonic_seconds() at the frame's release (see rate_hz).
/// Frames are released after `on_frame` returns, so memory stays bounded by the frames in flight.
SequenceRunStats run_sequence(FramePipeline& pipeline, const io::Sequence& sequence,
                              const SequenceRunOptions& options,
                              const std::function<void(const Frame&)>& on_frame);

}  // namespace meshflow
