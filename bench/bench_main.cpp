// The benchmark binary's main: Google Benchmark's, after the allocator policy the meshflow
// programs set first thing (runtime/process_heap.h), so that a benchmark runs on the heap the
// CLI runs on. Under oneTBB's malloc proxy (MESHFLOW_SCALABLE_MALLOC, the default for this
// binary) glibc's heap is not used and the call changes nothing; the run's context says which.
#include <benchmark/benchmark.h>

#include "runtime/process_heap.h"

int main(int argc, char** argv) {
  const bool tuned = meshflow::tune_process_heap();
  benchmark::AddCustomContext("process_heap", tuned ? "glibc, tuned" : "not tuned (other malloc)");
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
