#include "runtime/parallel.h"

#include <gtest/gtest.h>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <cstdint>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

#include "runtime/threads.h"

namespace meshflow {
namespace {

TEST(Parallel, SelectIndicesMatchesSerialFilter) {
  const std::size_t n = 3 * kParallelBlock + 17;
  const auto got = parallel_select_indices(n, [](std::size_t i) { return i % 7 == 3; });
  std::vector<std::uint32_t> want;
  for (std::size_t i = 0; i < n; ++i) {
    if (i % 7 == 3) want.push_back(static_cast<std::uint32_t>(i));
  }
  EXPECT_EQ(got, want);
}

// The determinism tests rely on ThreadLimit: the limit in force is the smallest live one, and
// under a limit of one a parallel loop runs on one thread.
TEST(Parallel, AThreadLimitHoldsAndTheSmallestLiveOneWins) {
  const auto allowed = [] {
    return tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
  };
  const auto threads_used = [] {
    std::mutex mutex;
    std::set<std::thread::id> ids;
    tbb::parallel_for(0, 20000, [&](int) {
      const std::lock_guard<std::mutex> lock(mutex);
      ids.insert(std::this_thread::get_id());
    });
    return ids.size();
  };
  {
    const ThreadLimit one(1);
    EXPECT_EQ(allowed(), 1u);
    EXPECT_EQ(threads_used(), 1u);
    const ThreadLimit two(2);  // while one lives, one still holds
    EXPECT_EQ(allowed(), 1u);
  }
  const ThreadLimit two(2);
  EXPECT_EQ(allowed(), std::min<std::size_t>(2, std::thread::hardware_concurrency()));
}

}  // namespace
}  // namespace meshflow
