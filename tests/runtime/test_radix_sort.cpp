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

TEST(RadixSort, CountingSortMatchesStdStableSortAndSkipsSentinels) {
  std::mt19937 rng(3);
  std::vector<std::uint16_t> key(200000);  // several parallel blocks
  for (auto& k : key) k = static_cast<std::uint16_t>(rng() % 40 == 0 ? 0xffff : rng() % 2048);
  std::vector<std::uint32_t> expected;
  for (std::uint32_t i = 0; i < key.size(); ++i)
    if (key[i] < 2048) expected.push_back(i);
  std::stable_sort(expected.begin(), expected.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return key[a] < key[b]; });
  auto key_of = [&](std::size_t i) { return std::size_t{key[i]}; };
  auto index = [](std::size_t i) { return static_cast<std::uint32_t>(i); };
  EXPECT_EQ(counting_sort<std::uint32_t>(key.size(), 2048, key_of, index), expected);
  // The stored values are value_of(i), here i with a tag in the top bit.
  const std::vector<std::uint64_t> tagged = counting_sort<std::uint64_t>(
      key.size(), 2048, key_of, [](std::size_t i) { return (std::uint64_t{1} << 63) | i; });
  ASSERT_EQ(tagged.size(), expected.size());
  for (std::size_t i = 0; i < tagged.size(); ++i)
    ASSERT_EQ(tagged[i], (std::uint64_t{1} << 63) | expected[i]);
  EXPECT_TRUE(counting_sort<std::uint32_t>(0, 2048, key_of, index).empty());
  // Into reused vectors, with each key's first item: key k's items are [starts[k], starts[k+1]).
  std::vector<std::uint32_t> sorted(7, 99);
  std::vector<std::size_t> starts;
  counting_sort(key.size(), 2048, key_of, index, sorted, starts);
  EXPECT_EQ(sorted, expected);
  ASSERT_EQ(starts.size(), 2049u);
  EXPECT_EQ(starts.front(), 0u);
  EXPECT_EQ(starts.back(), expected.size());
  for (std::size_t k = 0; k < 2048; ++k) {
    ASSERT_LE(starts[k], starts[k + 1]);
    for (std::size_t i = starts[k]; i < starts[k + 1]; ++i) ASSERT_EQ(key[sorted[i]], k);
  }
  counting_sort(0, 3, key_of, index, sorted, starts);
  EXPECT_TRUE(sorted.empty());
  EXPECT_EQ(starts, std::vector<std::size_t>(4, 0));
}

}  // namespace
}  // namespace meshflow
