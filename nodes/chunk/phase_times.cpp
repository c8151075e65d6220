#include "nodes/chunk/phase_times.h"

#include <sys/resource.h>

#include <ctime>

#include "runtime/tracing.h"

namespace meshflow::chunk {

double process_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

std::size_t peak_resident_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<std::size_t>(usage.ru_maxrss) * 1024;  // kilobytes on Linux
}

void PhaseClock::begin(const std::string& name, bool serial) {
  end();
  running_ = PhaseTime{};
  running_.name = name;
  running_.serial = serial;
  active_ = true;
  wall0_ = monotonic_seconds();
  cpu0_ = process_cpu_seconds();
}

void PhaseClock::end() {
  if (!active_) return;
  running_.wall_s = monotonic_seconds() - wall0_;
  running_.cpu_s = process_cpu_seconds() - cpu0_;
  running_.work_s = running_.waiting ? 0.0 : running_.cpu_s;
  phases_.push_back(running_);
  active_ = false;
}

void PhaseClock::wait(const std::string& name) {
  begin(name, false);
  running_.waiting = true;
}

double phase_wall(const std::vector<PhaseTime>& phases, const std::string& name) {
  double s = 0.0;
  for (const PhaseTime& p : phases)
    if (p.name == name) s += p.wall_s;
  return s;
}

double SerialFraction::speedup(double workers) const {
  if (!(workers > 0.0)) return 0.0;
  return 1.0 / (fraction + (1.0 - fraction) / workers);
}

SerialFraction serial_fraction(const std::vector<RankTimes>& ranks, double wall_s) {
  SerialFraction f;
  for (const RankTimes& r : ranks)
    for (const PhaseTime& p : r.phases) {
      if (p.serial)
        f.serial_s += p.wall_s;
      else
        f.parallel_work_s += p.work_s;
    }
  const double one_core = f.serial_s + f.parallel_work_s;
  if (one_core > 0.0) f.fraction = f.serial_s / one_core;
  if (f.fraction > 0.0) f.max_speedup = 1.0 / f.fraction;
  if (wall_s > 0.0) f.wall_share = f.serial_s / wall_s;
  return f;
}

}  // namespace meshflow::chunk
