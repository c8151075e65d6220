// The phases' clock and Amdahl's serial fraction of a chunked run (issue 61: the serial
// fraction measured from the ranks' own timings).

#include <gtest/gtest.h>

#include <cmath>

#include "nodes/chunk/phase_times.h"

namespace meshflow::chunk {
namespace {

// Burns at least `seconds` of this process's CPU time.
void phase_test_burn_cpu(double seconds) {
  const double start = process_cpu_seconds();
  volatile double sink = 0.0;
  while (process_cpu_seconds() - start < seconds) sink = sink + std::sqrt(sink + 1.0);
}

TEST(PhaseClock, TimesConsecutivePhasesAndCountsNoWorkWhileWaiting) {
  PhaseClock clock;
  clock.end();  // nothing runs: nothing recorded
  EXPECT_TRUE(clock.phases().empty());
  clock.begin("partition", false);
  phase_test_burn_cpu(0.003);
  clock.wait("plan");
  phase_test_burn_cpu(0.002);  // a rank spinning in MPI while it waits
  clock.begin("stitch", true);
  clock.end();
  clock.end();
  const std::vector<PhaseTime>& p = clock.phases();
  ASSERT_EQ(p.size(), 3u);
  EXPECT_EQ(p[0].name, "partition");
  EXPECT_FALSE(p[0].serial);
  EXPECT_GE(p[0].cpu_s, 0.003);
  EXPECT_EQ(p[0].work_s, p[0].cpu_s);
  EXPECT_EQ(p[1].name, "plan");
  EXPECT_TRUE(p[1].waiting);
  EXPECT_GE(p[1].cpu_s, 0.002);
  EXPECT_EQ(p[1].work_s, 0.0) << "waiting is no work";
  EXPECT_EQ(p[2].name, "stitch");
  EXPECT_TRUE(p[2].serial);
  for (const PhaseTime& t : p) EXPECT_GE(t.wall_s, 0.0) << t.name;
  EXPECT_EQ(phase_wall(p, "plan"), p[1].wall_s);
  EXPECT_EQ(phase_wall(p, "gather"), 0.0);
  EXPECT_GT(peak_resident_bytes(), std::size_t{1} << 20);
}

PhaseTime phase_test_phase(const char* name, double wall, double work, bool serial) {
  PhaseTime p;
  p.name = name;
  p.wall_s = p.cpu_s = wall;
  p.work_s = work;
  p.serial = serial;
  return p;
}

// Two ranks: T1 = serial wall (3 s) + parallel work (3 + 18 + 2 + 9 = 32 s) = 35 s.
TEST(SerialFraction, IsTheSerialWallOverTheOneCoreTime) {
  RankTimes r0, r1;
  r0.phases = {phase_test_phase("partition", 2, 3, false),
               phase_test_phase("chunks", 10, 18, false), phase_test_phase("stitch", 1, 1, true),
               phase_test_phase("finish", 2, 2, true)};
  r1.rank = 1;
  r1.phases = {phase_test_phase("partition", 2, 2, false), phase_test_phase("chunks", 10, 9, false),
               phase_test_phase("plan", 4, 0, false)};
  const SerialFraction f = serial_fraction({r0, r1}, 15.0);
  EXPECT_DOUBLE_EQ(f.serial_s, 3.0);
  EXPECT_DOUBLE_EQ(f.parallel_work_s, 32.0);
  EXPECT_DOUBLE_EQ(f.fraction, 3.0 / 35.0);
  EXPECT_DOUBLE_EQ(f.max_speedup, 35.0 / 3.0);
  EXPECT_DOUBLE_EQ(f.wall_share, 3.0 / 15.0);
  EXPECT_DOUBLE_EQ(f.speedup(1.0), 1.0);
  // n workers: 35 / (3 + 32 / n).
  EXPECT_NEAR(f.speedup(8.0), 35.0 / (3.0 + 32.0 / 8.0), 1e-12);
  EXPECT_LT(f.speedup(1e9), f.max_speedup);
  const SerialFraction none = serial_fraction({}, 0.0);
  EXPECT_EQ(none.fraction, 0.0);
  EXPECT_EQ(none.max_speedup, 0.0);
}

}  // namespace
}  // namespace meshflow::chunk
