#pragma once
// Progress lines on stderr for the long parts of a command (see progress_enabled()): rewritten
// in place on a terminal, a line every few seconds otherwise.

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <string>
#include <thread>

namespace meshflow::cli {

/// "12/100 frames  3.10 frames/s  ETA 28 s" for a sequence run; update() from one thread.
class FrameProgress {
 public:
  explicit FrameProgress(std::size_t total);
  /// `done` frames finished; prints at most every 0.25 s on a terminal, every 5 s otherwise.
  void update(std::size_t done);

 private:
  std::size_t total_;
  bool enabled_, tty_;
  double start_, last_ = -1e9;
};

/// "normals ... 1.4 s" for one job of named steps: a watcher thread prints every step once it
/// has run for a second (whatever was printed just before), and refreshes it until the next
/// step begins (every 0.25 s on a terminal, every 5 s otherwise). begin() may be called from
/// any thread (e.g. the flow graph's stages); the destructor stops the watcher.
class StepProgress {
 public:
  StepProgress();
  ~StepProgress();
  StepProgress(const StepProgress&) = delete;
  StepProgress& operator=(const StepProgress&) = delete;

  /// The step now running, optionally a sub-step ("optimize", "holes"; nullptr: none); copied.
  void begin(const std::string& step, const char* sub_step = nullptr);

 private:
  void watch();

  bool enabled_, tty_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::string step_, sub_step_;
  std::size_t step_number_ = 0;  // begin() calls so far: tells a new step from a refresh
  double step_start_ = 0.0;
  bool stop_ = false, printed_ = false;
  std::thread watcher_;
};

}  // namespace meshflow::cli
