#include "runtime/parallel.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

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

}  // namespace
}  // namespace meshflow
