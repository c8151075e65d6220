#include "serve/block_order.h"

#include <vector>

namespace meshflow::serve {

double block_distance2(const BlockKey& block, const BlockPoint& focus) {
  double d2 = 0.0;
  for (int a = 0; a < 3; ++a) {
    const double d = static_cast<double>(block[static_cast<std::size_t>(a)]) + 0.5 -
                     focus[static_cast<std::size_t>(a)];
    d2 += d * d;
  }
  return d2;
}

void NearestBlockQueue::set_focus(const BlockPoint& focus) {
  if (focus == focus_) return;
  focus_ = focus;
  std::vector<BlockKey> waiting;
  waiting.reserve(order_.size());
  for (const auto& entry : order_) waiting.push_back(entry.second);
  order_.clear();
  for (const BlockKey& key : waiting) order_.emplace(block_distance2(key, focus_), key);
}

bool NearestBlockQueue::push(const BlockKey& block) {
  return order_.emplace(block_distance2(block, focus_), block).second;
}

BlockKey NearestBlockQueue::pop() {
  const BlockKey key = order_.begin()->second;
  order_.erase(order_.begin());
  return key;
}

bool NearestBlockQueue::contains(const BlockKey& block) const {
  return order_.count({block_distance2(block, focus_), block}) > 0;
}

}  // namespace meshflow::serve
