#pragma once
// Thread-count control for the whole process (oneTBB global_control).

#include <tbb/global_control.h>

#include <memory>

namespace meshflow {

/// Number of hardware threads oneTBB would use by default.
int hardware_threads();

/// Caps the number of threads used by every meshflow kernel and graph while alive.
/// `threads` <= 0 means "all hardware threads". Create one near main(); not thread-safe.
class ThreadLimit {
 public:
  /// Limits oneTBB to `threads` workers (<= 0: every core) while this object lives.
  explicit ThreadLimit(int threads);
  /// The limit in force (every core's count when 0 was asked for).
  int threads() const { return threads_; }

 private:
  int threads_;
  std::unique_ptr<tbb::global_control> control_;
};

}  // namespace meshflow
