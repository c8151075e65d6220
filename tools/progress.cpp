#include "tools/progress.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>

#include "runtime/tracing.h"
#include "tools/console.h"

namespace meshflow::cli {

FrameProgress::FrameProgress(std::size_t total)
    : total_(total),
      enabled_(progress_enabled()),
      tty_(::isatty(::fileno(stderr)) != 0),
      start_(monotonic_seconds()) {}

void FrameProgress::update(std::size_t done) {
  if (!enabled_) return;
  const double now = monotonic_seconds();
  if (done < total_ && now - last_ < (tty_ ? 0.25 : 5.0)) return;
  last_ = now;
  const double elapsed = now - start_;
  const double rate = elapsed > 0.0 ? static_cast<double>(done) / elapsed : 0.0;
  const double eta = rate > 0.0 ? static_cast<double>(total_ - done) / rate : 0.0;
  std::fprintf(stderr, "%s%zu/%zu frames  %.2f frames/s  ETA %.0f s%s", tty_ ? "\r" : "", done,
               total_, rate, eta, tty_ ? "\033[K" : "\n");
  if (tty_ && done == total_) std::fputc('\n', stderr);
}

StepProgress::StepProgress() : enabled_(progress_enabled()), tty_(::isatty(::fileno(stderr)) != 0) {
  if (enabled_) watcher_ = std::thread([this] { watch(); });
}

StepProgress::~StepProgress() {
  if (!enabled_) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  watcher_.join();
  if (printed_ && tty_) std::fputs("\r\033[K", stderr);
}

void StepProgress::begin(const std::string& step, const char* sub_step) {
  if (!enabled_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  step_ = step;
  sub_step_ = sub_step != nullptr ? sub_step : "";
  ++step_number_;
  step_start_ = monotonic_seconds();
}

void StepProgress::watch() {
  std::unique_lock<std::mutex> lock(mutex_);
  double last_print = -1e9;
  std::size_t printed_step = 0;  // step_number_ of the step last printed (0: none)
  while (!stop_) {
    wake_.wait_for(lock, std::chrono::milliseconds(250));
    if (stop_ || step_number_ == 0) continue;
    const double now = monotonic_seconds();
    const double running = now - step_start_;
    // A step that has run for a second is printed at once; the same step again only after the
    // refresh interval.
    const bool new_step = printed_step != step_number_;
    if (running < 1.0 || (!new_step && now - last_print < (tty_ ? 0.25 : 5.0))) continue;
    last_print = now;
    printed_step = step_number_;
    printed_ = true;
    std::fprintf(stderr, "%s%s%s%s ... %.1f s%s", tty_ ? "\r" : "", step_.c_str(),
                 sub_step_.empty() ? "" : ": ", sub_step_.c_str(), running, tty_ ? "\033[K" : "\n");
  }
}

}  // namespace meshflow::cli
