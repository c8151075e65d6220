// Nearest changed blocks first (issue 56): the blocks a viewer waits for are sent ordered by the
// distance of their centres from the newest sensor position, ties by block coordinates, checked
// against a brute-force sort; and through the server, the order a client receives them in.

#include "serve/block_order.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <thread>
#include <tuple>
#include <vector>

#include "serve/server.h"
#include "tests/serve/test_client.h"

namespace meshflow::serve {
namespace {

using namespace std::chrono_literals;

// The brute-force order: every distinct block, by (squared distance of its centre, x, y, z).
std::vector<BlockKey> sorted_nearest_first(std::vector<BlockKey> blocks, const BlockPoint& focus) {
  std::sort(blocks.begin(), blocks.end());
  blocks.erase(std::unique(blocks.begin(), blocks.end()), blocks.end());
  const auto distance2 = [&focus](const BlockKey& b) {
    double d2 = 0.0;
    for (std::size_t a = 0; a < 3; ++a) d2 += (b[a] + 0.5 - focus[a]) * (b[a] + 0.5 - focus[a]);
    return d2;
  };
  std::stable_sort(blocks.begin(), blocks.end(), [&](const BlockKey& p, const BlockKey& q) {
    return distance2(p) < distance2(q);  // stable: equal distances keep the key order
  });
  return blocks;
}

std::vector<BlockKey> random_blocks(std::mt19937& random, std::size_t n, int extent) {
  std::uniform_int_distribution<int> coordinate(-extent, extent);
  std::vector<BlockKey> blocks(n);
  for (BlockKey& b : blocks) b = {coordinate(random), coordinate(random), coordinate(random)};
  return blocks;
}

TEST(BlockOrder, PopsNearestTheFocusFirstLikeABruteForceSort) {
  std::mt19937 random(56);
  std::uniform_real_distribution<double> position(-12.0, 12.0);
  for (int trial = 0; trial < 20; ++trial) {
    // Small extents give many duplicates and equal distances (ties).
    const std::vector<BlockKey> blocks = random_blocks(random, 400, trial % 2 ? 3 : 10);
    const BlockPoint focus{position(random), position(random), position(random)};
    NearestBlockQueue queue;
    queue.set_focus(focus);
    std::set<BlockKey> distinct;
    for (const BlockKey& b : blocks) EXPECT_EQ(queue.push(b), distinct.insert(b).second);
    ASSERT_EQ(queue.size(), distinct.size());
    std::vector<BlockKey> popped;
    while (!queue.empty()) popped.push_back(queue.pop());
    EXPECT_EQ(popped, sorted_nearest_first(blocks, focus)) << "trial " << trial;
  }
}

TEST(BlockOrder, ANewFocusReordersTheBlocksStillWaiting) {
  std::mt19937 random(7);
  const std::vector<BlockKey> blocks = random_blocks(random, 300, 8);
  NearestBlockQueue queue;
  queue.set_focus({-8.0, -8.0, -8.0});
  for (const BlockKey& b : blocks) queue.push(b);
  std::set<BlockKey> sent;
  for (int i = 0; i < 50; ++i) sent.insert(queue.pop());
  const BlockPoint moved{8.0, 8.0, 8.0};  // the sensor went to the opposite corner
  queue.set_focus(moved);
  std::vector<BlockKey> waiting;
  for (const BlockKey& b : blocks)
    if (!sent.count(b)) waiting.push_back(b);
  std::vector<BlockKey> popped;
  while (!queue.empty()) popped.push_back(queue.pop());
  EXPECT_EQ(popped, sorted_nearest_first(waiting, moved));
}

TEST(BlockOrder, EqualDistancesGoByBlockCoordinates) {
  NearestBlockQueue queue;
  queue.set_focus({0.5, 0.5, 0.5});  // the centre of block (0, 0, 0)
  for (const BlockKey& b : std::vector<BlockKey>{
           {1, 0, 0}, {0, 0, 1}, {0, -1, 0}, {0, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, 0, -1}})
    queue.push(b);
  const std::vector<BlockKey> expected = {{0, 0, 0}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1},
                                          {0, 0, 1}, {0, 1, 0},  {1, 0, 0}};
  std::vector<BlockKey> popped;
  while (!queue.empty()) popped.push_back(queue.pop());
  EXPECT_EQ(popped, expected);
  EXPECT_DOUBLE_EQ(block_distance2({2, 0, -1}, {0.5, 0.5, 0.5}), 2.0 * 2.0 + 0.0 + 1.0);
}

// The blocks a client is sent, in the order of the batches, up to the end message.
std::vector<BlockKey> blocks_received(testing::Client& client) {
  std::vector<BlockKey> order;
  std::string message;
  bool binary = false;
  for (;;) {
    if (client.read(message, binary)) {
      ADD_FAILURE() << "the stream ended without the end message";
      return order;
    }
    if (!binary) {
      if (nlohmann::json::parse(message)["type"] == "end") return order;
      continue;
    }
    std::uint32_t count = 0;
    std::memcpy(&count, message.data() + 4, 4);
    std::size_t at = 8;
    for (std::uint32_t i = 0; i < count; ++i) {
      BlockKey key{};
      std::memcpy(key.data(), message.data() + at, 12);
      std::uint32_t n = 0;
      std::memcpy(&n, message.data() + at + 12, 4);
      at += 16 + n;
      order.push_back(key);
    }
  }
}

TEST(BlockOrder, TheServerSendsAClientsBlocksNearestTheNewestSensorPositionFirst) {
  ServerConfig config = testing::config_with_page();
  config.chunk_bytes = 64;  // a few blocks per batch: the order is the queue's, not one batch's
  Server server{config};
  std::mt19937 random(3);
  std::vector<BlockKey> first = random_blocks(random, 150, 6);
  std::vector<BlockKey> second = random_blocks(random, 150, 6);
  const auto publish = [&server](const std::vector<BlockKey>& keys, const BlockPoint& focus) {
    std::vector<MapBlock> blocks;
    for (const BlockKey& k : keys)
      blocks.push_back({k[0], k[1], k[2], std::make_shared<const std::string>(20, 'b')});
    server.publish_blocks(std::move(blocks), focus);
  };
  publish(first, {-6.0, 0.0, 0.0});
  const BlockPoint newest{5.0, 5.0, -5.0};
  publish(second, newest);  // the sensor moved: the newest position orders everything waiting
  server.finish();
  std::this_thread::sleep_for(300ms);  // both publications reach the I/O thread
  testing::Client client;
  ASSERT_FALSE(client.connect(server.port()));
  std::vector<BlockKey> all = first;
  all.insert(all.end(), second.begin(), second.end());
  EXPECT_EQ(blocks_received(client), sorted_nearest_first(all, newest));
}

}  // namespace
}  // namespace meshflow::serve
