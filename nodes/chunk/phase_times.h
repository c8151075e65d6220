#pragma once
// Wall and CPU time of the phases of a chunked reconstruction on one process (one MPI rank),
// and the serial fraction (Amdahl's law) that every rank's phases imply.

#include <cstddef>
#include <string>
#include <vector>

namespace meshflow::chunk {

/// CPU seconds this process has used so far, all its threads together
/// (CLOCK_PROCESS_CPUTIME_ID). Thread-safe. O(1).
double process_cpu_seconds();

/// The most resident memory this process has held so far, bytes (getrusage's ru_maxrss).
/// Thread-safe. O(1).
std::size_t peak_resident_bytes();

/// One phase of a chunked run on one process.
struct PhaseTime {
  std::string name;     ///< "decide", "partition", "chunks", "gather", "stitch", "finish", "write"
  double wall_s = 0.0;  ///< seconds from its start to its end (monotonic clock)
  double cpu_s = 0.0;   ///< CPU seconds of the whole process (all threads) over that span
  /// Seconds of work it did: cpu_s, or 0 when the process only waited (an MPI rank waiting for
  /// another's message may spin on its core: CPU time, but no work).
  double work_s = 0.0;
  bool serial = false;   ///< runs on one core of one process while every other worker waits
  bool waiting = false;  ///< the process only waited for others (PhaseClock::wait)
};

/// Times the consecutive phases of one process: begin() ends the running phase (if any) and
/// starts the next; end() ends it. Not thread-safe. O(1) per call.
class PhaseClock {
 public:
  /// Ends the running phase and starts `name`.
  void begin(const std::string& name, bool serial);
  /// Ends the running phase and starts `name`, in which this process only waits for others
  /// (its work counts 0).
  void wait(const std::string& name);
  /// Ends the running phase (nothing when none runs).
  void end();
  /// The phases ended so far, in order.
  const std::vector<PhaseTime>& phases() const { return phases_; }

 private:
  std::vector<PhaseTime> phases_;
  PhaseTime running_;
  bool active_ = false;
  double wall0_ = 0.0, cpu0_ = 0.0;
};

/// Wall seconds of the phases named `name` in `phases` (summed; 0 when there is none). O(n).
double phase_wall(const std::vector<PhaseTime>& phases, const std::string& name);

/// One process's share of a chunked run, as its --json reports it.
struct RankTimes {
  int rank = 0;
  std::size_t chunks = 0;         ///< chunks this process meshed
  std::size_t peak_bytes = 0;     ///< peak_resident_bytes() at its end
  std::vector<PhaseTime> phases;  ///< in order
};

/// Amdahl's law from the ranks' measured phases. The run's one-core time is estimated as
/// T1 = serial_s + parallel_work_s: the serial phases as they ran, plus the work of every rank's
/// parallel phases (which would run one after another on one core).
struct SerialFraction {
  double serial_s = 0.0;         ///< wall seconds of the serial phases (all ranks)
  double parallel_work_s = 0.0;  ///< work seconds of the parallel phases, all ranks together
  double fraction = 0.0;         ///< serial_s / T1: Amdahl's serial fraction f (0 when T1 = 0)
  double max_speedup = 0.0;      ///< 1 / f: what no number of cores or nodes exceeds (0: f = 0)
  double wall_share = 0.0;       ///< serial_s / wall_s: the serial share of this run's wall time
  /// T1 / (f T1 + (1 - f) T1 / n) for n workers (Amdahl's predicted speedup). O(1).
  double speedup(double workers) const;
};

/// The serial fraction of a run of wall time `wall_s` from every rank's phases. O(phases).
SerialFraction serial_fraction(const std::vector<RankTimes>& ranks, double wall_s);

}  // namespace meshflow::chunk
