#pragma once
// The order in which a viewer is sent the blocks of a fused map that changed since its last
// update: nearest first to the newest sensor position (what the sensor sees now appears first),
// ties by block coordinates (x, then y, then z), so the order is deterministic.

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <set>
#include <utility>

namespace meshflow::serve {

/// A block of a fused map by its block coordinates (TsdfVolume's: voxel index floor-divided by 8).
using BlockKey = std::array<std::int32_t, 3>;

/// A point in block units: world metres / (voxel size * 8), so block (x, y, z) spans
/// [x, x + 1) on the first axis and its centre is x + 0.5.
using BlockPoint = std::array<double, 3>;

/// The squared distance, in block units, from `block`'s centre to `focus`. O(1).
double block_distance2(const BlockKey& block, const BlockPoint& focus);

/// The blocks waiting to be sent to one viewer, each at most once, taken nearest to the focus
/// first (block_distance2(), ties by key). Until a focus is set it is the origin. Not
/// thread-safe (one viewer's, on the server's I/O thread).
class NearestBlockQueue {
 public:
  /// Moves the focus (the newest sensor position, block units); the waiting blocks are
  /// re-ordered. O(n log n) for n waiting blocks.
  void set_focus(const BlockPoint& focus);
  const BlockPoint& focus() const { return focus_; }

  /// Adds `block`; false (nothing changes) when it is already waiting. O(log n).
  bool push(const BlockKey& block);
  /// Removes and returns the waiting block nearest the focus (ties: the smallest key). The
  /// queue must not be empty. O(log n).
  BlockKey pop();
  /// Whether `block` is waiting. O(log n).
  bool contains(const BlockKey& block) const;

  bool empty() const { return order_.empty(); }
  std::size_t size() const { return order_.size(); }

 private:
  BlockPoint focus_{0.0, 0.0, 0.0};
  std::set<std::pair<double, BlockKey>> order_;  // (distance², key): nearest first
};

}  // namespace meshflow::serve
