#include "runtime/tracing.h"

#include <gtest/gtest.h>

#include "runtime/parallel.h"

namespace meshflow {
namespace {

TEST(Tracing, SummarizesStagesInFirstSeenOrder) {
  std::vector<StageRecord> records = {
      {"b", 0.0, 0.2, 0, 10}, {"a", 0.0, 0.1, 0, 5}, {"b", 1.0, 1.4, 1, 10}};
  const auto s = summarize_stages(records);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].stage, "b");
  EXPECT_EQ(s[0].calls, 2u);
  EXPECT_NEAR(s[0].total_s, 0.6, 1e-12);
  EXPECT_NEAR(s[0].max_s, 0.4, 1e-12);
  EXPECT_EQ(s[0].items, 20u);
  EXPECT_NE(format_stage_table(s, 1.0).find("b"), std::string::npos);
}

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
