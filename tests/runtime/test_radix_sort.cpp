#include "runtime/radix_sort.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace meshflow {
namespace {

TEST(RadixSort, MatchesStdSortOnWideAndNarrowKeys) {
  std::mt19937_64 rng(9);
  for (std::uint64_t range : {std::uint64_t{1000}, std::uint64_t{1} << 40, ~std::uint64_t{0}}) {
    std::vector<std::uint64_t> keys(300000);  // several parallel blocks
    for (auto& k : keys) k = rng() % range + (range < 1000000 ? (std::uint64_t{7} << 50) : 0);
    std::vector<std::uint64_t> expected = keys;
    std::sort(expected.begin(), expected.end());
    radix_sort(keys);
    EXPECT_EQ(keys, expected);
    radix_sort_unique(keys);
    expected.erase(std::unique(expected.begin(), expected.end()), expected.end());
    EXPECT_EQ(keys, expected);
  }
  std::vector<std::uint64_t> empty;
  radix_sort(empty);
  EXPECT_TRUE(empty.empty());
}

}  // namespace
}  // namespace meshflow
